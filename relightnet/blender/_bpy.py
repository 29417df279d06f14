"""Access to Blender's Python module (``bpy``, the optional ``relightnet[blender]`` extra).

``bpy`` is one global Blender session per process: every scene built here starts from
:func:`reset` (factory settings, empty scene). Importing it prints a numpy-ABI message of its sound
module (audaspace, built for NumPy 1.x, unused here: reduced to one DEBUG line) and Blender
logs lines to stdout while saving and rendering; :func:`quiet` captures those
file-descriptor writes and logs them at DEBUG level.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import tempfile
from collections.abc import Iterator

from ..checks import InputError

logger = logging.getLogger(__name__)

#: The bpy release relightnet is tested with (PyPI wheel, Python 3.11 only).
BPY_VERSION = "5.0.1"


@contextlib.contextmanager
def quiet(fds: tuple[int, ...] = (1, 2)) -> Iterator[None]:
    """Capture writes to the given OS file descriptors (C code included) and to Python's
    ``sys.stdout``/``sys.stderr`` (whatever they are); log them at DEBUG."""
    import io

    for s in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            s.flush()
    saved = {fd: os.dup(fd) for fd in fds}
    py = io.StringIO()
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        try:
            for fd in fds:
                os.dup2(tmp.fileno(), fd)
            with contextlib.redirect_stdout(py if 1 in fds else sys.stdout), \
                    contextlib.redirect_stderr(py if 2 in fds else sys.stderr):
                yield
        finally:
            for fd, old in saved.items():
                os.dup2(old, fd)
                os.close(old)
            tmp.seek(0)
            text = (tmp.read().decode("utf-8", "replace") + py.getvalue()).strip()
            if "numpy.core.multiarray failed to import" in text:  # bpy's sound module (audaspace), built for
                # NumPy 1.x, does not load under NumPy 2 and says so at length; Blender runs on without sound,
                # which relightnet never uses: one line instead of the message, even at DEBUG
                text = ""
                logger.debug("bpy: its sound module did not load (built for NumPy 1.x); sound is not used")
            if text:
                logger.debug("blender output:\n%s", text)


def import_bpy():
    """Import ``bpy`` (quietly) or raise :class:`InputError` saying how to install it."""
    if "bpy" in sys.modules:
        return sys.modules["bpy"]
    try:
        with quiet():
            import bpy
    except ImportError as e:
        raise InputError(
            f"Blender support needs the 'bpy' module (pip install 'relightnet[blender]', bpy=={BPY_VERSION}, "
            f"Python 3.11): {e}"
        ) from None
    _drop_session_tempdir(bpy)
    bpy.context.preferences.filepaths.use_scripts_auto_execute = False  # a .blend's scripts never run
    return bpy


def _drop_session_tempdir(bpy) -> None:
    """Remove the folder Blender makes in TMPDIR when it is imported (``bpy.app.tempdir``) while it is empty.

    Blender removes it at a normal exit only, so a killed render left it behind. relightnet never needs it
    (renders are saved to named files; Blender does not make it again), so once it is gone a killed process
    leaves nothing in TMPDIR.
    """
    folder = bpy.app.tempdir
    if folder and os.path.basename(os.path.normpath(folder)).startswith("blender_"):
        with contextlib.suppress(OSError):  # not empty, or gone already: left to Blender
            os.rmdir(folder)


def reset():
    """Start an empty Blender session (factory settings, no objects); returns ``bpy``."""
    bpy = import_bpy()
    with quiet((1,)):
        bpy.ops.wm.read_factory_settings(use_empty=True)
    _drop_session_tempdir(bpy)  # factory settings make Blender's TMPDIR folder again
    bpy.context.preferences.filepaths.use_scripts_auto_execute = False
    return bpy
