"""Test package (module names may repeat across folders: tests/<subpackage>/test_<module>.py mirrors relightnet)."""
