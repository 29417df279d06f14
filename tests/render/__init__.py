"""Tests of relightnet.render (a package, so that test module names may repeat across folders)."""
