"""How much a file may make relightnet decode: the limits checked before any decoding.

Three limits, each with an environment variable to raise it (the commands' ``--max-pixels``
option sets the first for their run):

- :func:`max_pixels`: width × height of one image or video frame, read from the file's
  header before a pixel is decoded (default 12.5 megapixels: what the 2 GiB memory budget
  of the video commands holds, measured; ``RELIGHTNET_MAX_PIXELS``);
- :func:`max_array_bytes`: the bytes an ``.npz`` / ``.npy`` file may expand to in memory
  (default 4 GiB; ``RELIGHTNET_MAX_ARRAY_BYTES``), checked from its headers before reading;
- :func:`max_pixels_per_byte`: how many pixels a video may decode to per byte of its file
  (default 20,000; ``RELIGHTNET_MAX_PIXELS_PER_BYTE``), checked from its packets before its
  first frame is used (:func:`check_video_expansion`): a 460 KB GIF of 20,000 one-pixel frames
  on a 9 MP screen is 180 billion pixels of work; a camera's video is below 100 per byte.

Peak memory of a reader stays a small multiple of these limits whatever the file claims.
"""

from __future__ import annotations

import os

from ..errors import InputError

__all__ = ["DEFAULT_MAX_PIXELS", "DEFAULT_MAX_ARRAY_BYTES", "DEFAULT_MAX_PIXELS_PER_BYTE", "max_pixels",
           "max_array_bytes", "max_pixels_per_byte", "check_pixels", "check_video_expansion", "set_max_pixels"]

DEFAULT_MAX_PIXELS = 12_500_000
DEFAULT_MAX_ARRAY_BYTES = 4 << 30
DEFAULT_MAX_PIXELS_PER_BYTE = 20_000
#: A video that decodes to fewer pixels than this many frames at the pixel limit is never refused
#: for its expansion (short clips of flat colour compress to almost nothing, and cost little).
EXPANSION_FREE_FRAMES = 10
_PIXELS_ENV, _BYTES_ENV, _RATIO_ENV = "RELIGHTNET_MAX_PIXELS", "RELIGHTNET_MAX_ARRAY_BYTES", \
    "RELIGHTNET_MAX_PIXELS_PER_BYTE"


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


def max_pixels_per_byte() -> int:
    """Most pixels a video may decode to per byte of its file (``RELIGHTNET_MAX_PIXELS_PER_BYTE``, default 20,000)."""
    return _positive(_RATIO_ENV, DEFAULT_MAX_PIXELS_PER_BYTE)


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


def check_video_expansion(frames: int, width: int, height: int, file_bytes: int, what: str) -> None:
    """Refuse a video whose frames (counted from its packets) decode to more than
    :func:`max_pixels_per_byte` pixels per byte of its file: a decompression bomb, thousands of
    frames that are a few bytes each, whose work no small file should ask for. Videos decoding
    to less than :data:`EXPANSION_FREE_FRAMES` frames at the pixel limit pass whatever their size.

    Raises:
        InputError: ``"clip.gif: 20000 frames of 3000x3000 from 460 KB (391,304 pixels per byte ..."``.
    """
    pixels = int(frames) * int(width) * int(height)
    if pixels <= EXPANSION_FREE_FRAMES * max_pixels():
        return
    ratio, limit = pixels / max(int(file_bytes), 1), max_pixels_per_byte()
    if ratio > limit:
        raise InputError(
            f"{what}: {frames} frames of {width}x{height} from {file_bytes / 1e3:,.0f} KB ({ratio:,.0f} pixels per "
            f"byte of file, above the limit of {limit:,}): a decompression bomb; raise the limit with "
            f"{_RATIO_ENV} if the file is trusted"
        )
