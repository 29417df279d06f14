"""How much a file may make relightnet decode: the limits checked before any decoding.

Two limits, each with an environment variable to raise it (the commands' ``--max-pixels``
option sets the first for their run):

- :func:`max_pixels`: width × height of one image or video frame, read from the file's
  header before a pixel is decoded (default 12.5 megapixels: what the 2 GiB memory budget
  of ``relight-image`` holds, measured; ``RELIGHTNET_MAX_PIXELS``);
- :func:`max_array_bytes`: the bytes an ``.npz`` / ``.npy`` file may expand to in memory
  (default 4 GiB; ``RELIGHTNET_MAX_ARRAY_BYTES``), checked from its headers before reading.

Peak memory of a reader stays a small multiple of these limits whatever the file claims.
"""

from __future__ import annotations

import os

from ..errors import InputError

__all__ = ["DEFAULT_MAX_PIXELS", "DEFAULT_MAX_ARRAY_BYTES", "max_pixels", "max_array_bytes", "check_pixels",
           "set_max_pixels"]

DEFAULT_MAX_PIXELS = 12_500_000
DEFAULT_MAX_ARRAY_BYTES = 4 << 30
_PIXELS_ENV, _BYTES_ENV = "RELIGHTNET_MAX_PIXELS", "RELIGHTNET_MAX_ARRAY_BYTES"


def _positive(env: str, default: int) -> int:
    text = os.environ.get(env, "").strip()
    if not text:
        return default
    try:
        value = int(float(text))
    except ValueError:
        value = 0
    if value < 1:
        raise InputError(f"{env}={text}: expected a positive number")
    return value


def max_pixels() -> int:
    """Largest width × height decoded (``RELIGHTNET_MAX_PIXELS``, default 12.5 megapixels)."""
    return _positive(_PIXELS_ENV, DEFAULT_MAX_PIXELS)


def max_array_bytes() -> int:
    """Largest in-memory size of the arrays read from one ``.npz``/``.npy`` (default 4 GiB)."""
    return _positive(_BYTES_ENV, DEFAULT_MAX_ARRAY_BYTES)


def set_max_pixels(n: int) -> None:
    """Set :func:`max_pixels` for this process and the processes it starts."""
    if int(n) < 1:
        raise InputError(f"--max-pixels {n}: expected a positive number")
    os.environ[_PIXELS_ENV] = str(int(n))


def check_pixels(width: int, height: int, what: str) -> None:
    """Refuse an image or frame above :func:`max_pixels` (or with a non-positive side) before decoding it.

    Raises:
        InputError: ``"photo.png: 12000x12000 pixels (144.0 MP) is above the limit of 12.5 MP ..."``.
    """
    limit = max_pixels()
    if width < 1 or height < 1:
        raise InputError(f"{what}: the header says {width}x{height} pixels; expected a positive size")
    if width * height > limit:
        raise InputError(
            f"{what}: {width}x{height} pixels ({width * height / 1e6:.1f} MP) is above the limit of "
            f"{limit / 1e6:.1f} MP; raise it with --max-pixels or {_PIXELS_ENV} if the file is trusted"
        )
