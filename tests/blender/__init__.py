"""Tests of relightnet.blender (a package: its basenames repeat those of tests/sh and tests/raster)."""
