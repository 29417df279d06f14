"""Tests of relightnet.distributed (a package, so that test module names may repeat across folders)."""
