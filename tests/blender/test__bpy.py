"""The bpy access layer: C-level output is captured; bpy's NumPy-ABI noise is one DEBUG line; reset empties."""

import logging
import os

from relightnet.blender._bpy import import_bpy, quiet, reset

ABI = (b"A module that was compiled using NumPy 1.x cannot be run in\nNumPy 2.4.6 as it may crash.\n"
       b"Traceback (most recent call last):\n  File \"x\", line 1\nImportError: numpy.core.multiarray failed to "
       b"import\nUnable to initialise audio\n")


def test_quiet_captures_file_descriptor_writes(caplog, capfd):
    with caplog.at_level(logging.DEBUG, logger="relightnet.blender._bpy"), quiet():
        os.write(1, b"Blender says hello\n")
    assert "Blender says hello" in caplog.text
    assert capfd.readouterr().out == ""


def test_the_numpy_abi_message_of_bpys_sound_module_is_one_line(caplog, capfd):
    with caplog.at_level(logging.DEBUG, logger="relightnet.blender._bpy"), quiet():
        os.write(2, ABI)
    assert "sound module did not load" in caplog.text
    assert "numpy.core.multiarray" not in caplog.text and "Traceback" not in caplog.text
    assert capfd.readouterr().err == ""


def test_import_bpy_prints_nothing(capfd):
    bpy = import_bpy()
    assert hasattr(bpy, "ops")
    out = capfd.readouterr()
    assert out.out == "" and out.err == ""


def test_quiet_captures_only_the_descriptors_it_is_given(caplog, capfd):
    with caplog.at_level(logging.DEBUG, logger="relightnet.blender._bpy"), quiet((1,)):
        os.write(1, b"to the log\n")
        os.write(2, b"to stderr\n")
    assert "to the log" in caplog.text and "to stderr" not in caplog.text
    out = capfd.readouterr()
    assert out.out == "" and out.err == "to stderr\n"


def test_reset_starts_an_empty_scene(capfd):
    bpy = reset()
    bpy.ops.mesh.primitive_cube_add()
    assert len(bpy.data.objects) == 1
    assert reset() is bpy and len(bpy.data.objects) == 0 and len(bpy.data.meshes) == 0
    out = capfd.readouterr()
    assert out.out == ""
