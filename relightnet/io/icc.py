"""ICC colour profiles of photos: read from the file, converted to and from sRGB, embedded in PNGs.

relightnet works in sRGB (linear inside, docs/design.md). A photo with an embedded RGB profile that
is not sRGB (Display-P3 from a phone, Adobe RGB from a camera) is converted to sRGB when it is read,
and an output made from it (``relight-image``) is converted back and carries the same ICC bytes: a
Display-P3 photo relit stays a Display-P3 file, and where nothing changed a colour-managed viewer
shows it as it was, to 8-bit rounding. The conversions are LittleCMS's (Pillow's ImageCms) with the
relative colorimetric intent, the same both ways: a colour inside sRGB keeps its value exactly (no
gamut compression), a colour outside sRGB (a P3 red more saturated than sRGB's) is clipped to the sRGB
cube, and stays so in the output. They run on 8-bit values: a 16-bit image with a non-sRGB profile is
converted at 8-bit precision (with a warning). A profile that is sRGB (any of its variants: it maps a
test chart to itself within one code) is not applied, so such a photo decodes bit for bit as an
untagged one. A damaged profile, or one not for RGB data (gray, CMYK), is a warning and sRGB assumed.
"""

from __future__ import annotations

import io
import logging
import struct
import warnings
import zlib
from functools import lru_cache

import numpy as np

logger = logging.getLogger(__name__)

__all__ = ["read_icc", "check_profile", "photo_profile", "profile_to_srgb", "srgb_to_profile", "embed_icc"]

#: A profile whose transform to sRGB moves no value of :func:`_chart` by more than this many 8-bit
#: codes is sRGB (the variants differ in how their curves are stored, by up to one code).
SRGB_TOLERANCE = 1


def read_icc(path) -> bytes | None:
    """The ICC profile embedded in an image file (JPEG APP2, PNG iCCP, WebP, TIFF, ...), or None.

    Only the file's header is parsed (Pillow, no pixel is decoded); a file Pillow cannot parse
    has no profile to it.
    """
    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # Pillow's decompression-bomb warning: the caller checked the size
            with Image.open(path) as im:
                icc = im.info.get("icc_profile")
    except Image.DecompressionBombError:
        logger.warning("%s: its ICC profile was not read (the image is larger than Pillow opens); "
                       "read as sRGB", path)
        return None
    except Exception:  # any format Pillow does not know, or a header it cannot parse: no profile to read
        return None
    return bytes(icc) if icc else None


@lru_cache(maxsize=8)
def _profile(icc: bytes):
    """The parsed RGB profile of ``icc`` and whether it is sRGB; ValueError when unusable."""
    from PIL import ImageCms

    try:
        prof = ImageCms.ImageCmsProfile(io.BytesIO(icc))
    except (ImageCms.PyCMSError, OSError, TypeError, ValueError) as e:
        raise ValueError(f"damaged ({e})") from None
    space = prof.profile.xcolor_space.strip()
    if space != "RGB":
        raise ValueError(f"a {space or 'unknown'} profile, not RGB")
    try:
        to_srgb = _transform(prof, ImageCms.createProfile("sRGB"))
        to_prof = _transform(ImageCms.createProfile("sRGB"), prof)
    except (ImageCms.PyCMSError, OSError, ValueError) as e:
        raise ValueError(f"unusable ({e})") from None
    chart = _chart()
    moved = np.abs(_apply(to_srgb, chart).astype(np.int16) - chart).max()
    return to_srgb, to_prof, bool(moved <= SRGB_TOLERANCE)


def _transform(src, dst):
    from PIL import ImageCms

    return ImageCms.buildTransform(src, dst, "RGB", "RGB",
                                   renderingIntent=ImageCms.Intent.RELATIVE_COLORIMETRIC)


def _chart() -> np.ndarray:
    """(1, 1280, 3) uint8: the gray ramp, each primary's ramp and a ramp of a secondary colour."""
    v = np.arange(256, dtype=np.uint8)
    z = np.zeros_like(v)
    rows = [np.stack(c, -1) for c in ((v, v, v), (v, z, z), (z, v, z), (z, z, v), (v, v, z))]
    return np.concatenate(rows)[None]


def _apply(transform, rgb: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 through a LittleCMS transform."""
    from PIL import Image, ImageCms

    out = ImageCms.applyTransform(Image.fromarray(np.ascontiguousarray(rgb), "RGB"), transform)
    return np.asarray(out)


def _usable(icc: bytes | None, name) -> tuple | None:
    """``_profile(icc)`` or None (no profile, or unusable: warned)."""
    if not icc:
        return None
    try:
        return _profile(bytes(icc))
    except ValueError as e:
        logger.warning("%s: its ICC profile is %s; sRGB assumed", name, e)
        return None


def check_profile(icc: bytes | None, name="image") -> bytes | None:
    """``icc`` when it is a usable RGB profile, else None (a damaged or non-RGB one: a warning naming ``name``)."""
    return None if _usable(icc, name) is None else bytes(icc)


def photo_profile(path) -> bytes | None:
    """The ICC profile an output made from the photo at ``path`` carries: its embedded RGB profile
    (sRGB ones included), or None when it has none or an unusable one (which the reader warned about)."""
    icc = read_icc(path)
    if icc is None:
        return None
    try:
        _profile(icc)
    except ValueError:
        return None
    return icc


def profile_to_srgb(rgb: np.ndarray, icc: bytes | None, name="image") -> np.ndarray:
    """Pixels encoded in the ICC profile ``icc`` → sRGB (relative colorimetric, module docstring).

    Args:
        rgb: (H, W, 3) uint8 or uint16 values in the profile's encoding.
        icc: the profile's bytes; None, an sRGB profile or an unusable one (a warning naming
            ``name``) leave the pixels as they are.

    Returns:
        (H, W, 3) sRGB values of the same dtype (the input itself when nothing is converted).
    """
    found = _usable(icc, name)
    if found is None or found[2]:
        return rgb
    if rgb.dtype == np.uint8:
        return _apply(found[0], rgb)
    logger.warning("%s: a 16-bit image with a non-sRGB ICC profile: converted to sRGB at 8-bit precision", name)
    eight = (rgb.astype(np.float32) / 257).round().astype(np.uint8)
    return _apply(found[0], eight).astype(np.uint16) * 257


def srgb_to_profile(rgb: np.ndarray, icc: bytes | None, name="image") -> np.ndarray:
    """The inverse of :func:`profile_to_srgb` on 8-bit values.

    Args:
        rgb: (H, W, 3) uint8 sRGB.
        icc: the destination profile (None, sRGB or unusable: unchanged).

    Returns:
        (H, W, 3) uint8 in the profile's encoding.
    """
    found = _usable(icc, name)
    return rgb if found is None or found[2] else _apply(found[1], rgb)


def embed_icc(png: bytes, icc: bytes, name: str = "ICC profile") -> bytes:
    """A PNG file's bytes with an ``iCCP`` chunk (the profile, zlib-compressed) right after ``IHDR``.

    Args:
        png: a PNG file without colour-space chunks (``iCCP``, ``sRGB``), as FFmpeg's encoder writes.
        icc: the profile's bytes.
        name: the profile name stored in the chunk (1 to 79 Latin-1 characters).
    """
    if png[:8] != b"\x89PNG\r\n\x1a\n" or png[12:16] != b"IHDR":
        raise ValueError("not a PNG file starting with its IHDR chunk")
    body = name.encode("latin-1")[:79] + b"\x00\x00" + zlib.compress(icc, 9)
    chunk = struct.pack(">I", len(body)) + b"iCCP" + body + struct.pack(">I", zlib.crc32(b"iCCP" + body))
    end = 8 + 12 + struct.unpack(">I", png[8:12])[0]
    return png[:end] + chunk + png[end:]
