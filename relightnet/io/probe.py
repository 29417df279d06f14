"""Image sizes read from file headers, before anything is decoded.

:func:`header_size` knows the common still-image formats (PNG, JPEG, GIF, BMP, WebP, TIFF,
OpenEXR, Radiance HDR, PNM, QOI) and reads a few hundred bytes of them (a JPEG's markers
are walked to its frame header). For other formats it returns None and the decoder's own
``max_pixels`` check (:func:`relightnet.io.limits.max_pixels`) stops an oversized image.
"""

from __future__ import annotations

import re
import struct
import zlib
from pathlib import Path

from ..errors import InputError
from .limits import check_pixels

__all__ = ["PHOTO_SUFFIXES", "IMAGE_OUT_SUFFIXES", "header_size", "check_image_file", "check_png_chunks",
           "MAX_PNG_METADATA"]

#: The file types read as a photo (lower case): what FFmpeg decodes as one still image. HEIC/HEIF
#: are read where the FFmpeg build demuxes them; a file it cannot read is refused in one line.
PHOTO_SUFFIXES = (".png", ".jpg", ".jpeg", ".webp", ".avif", ".heic", ".heif", ".tif", ".tiff", ".bmp")
#: The file types an image is written as (:func:`relightnet.io.write_image`): PNG lossless, JPEG and
#: WebP at a quality.
IMAGE_OUT_SUFFIXES = (".png", ".jpg", ".jpeg", ".webp")

_HEAD = 1 << 16
#: Most bytes of text and metadata (tEXt, zTXt, iTXt, iCCP, eXIf; decompressed) a PNG may carry.
#: FFmpeg's decoder expands every text chunk into the frame's metadata, so a 1 MB zTXt
#: chunk could otherwise become a gigabyte before the first pixel.
MAX_PNG_METADATA = 8 << 20
_PNG_META = (b"tEXt", b"zTXt", b"iTXt", b"iCCP", b"eXIf")


def header_size(path: str | Path) -> tuple[int, int] | None:
    """(width, height) from an image file's header, or None for an unknown or unreadable header.

    The numbers are what the header says, unchecked (zero, negative or huge values are
    returned as they are for the caller to judge).
    """
    with open(path, "rb") as f:
        head = f.read(_HEAD)
        for sig, reader in _READERS:
            if head.startswith(sig):
                try:
                    return reader(head, f)
                except (struct.error, ValueError, IndexError):
                    return None
    return None


def _png(head: bytes, f) -> tuple[int, int] | None:
    if head[12:16] != b"IHDR":
        return None
    return struct.unpack(">II", head[16:24])


def _inflated(data: bytes, start: int, budget: int) -> int:
    """Bytes the zlib stream at ``data[start:]`` inflates to, counting at most ``budget + 1``."""
    z, n, rest = zlib.decompressobj(), 0, data[start:]
    try:
        while rest and n <= budget:
            n += len(z.decompress(rest, 1 << 16))
            rest = z.unconsumed_tail
    except zlib.error:
        return n  # a damaged stream: the decoder reports it (or skips the chunk)
    return n


def _metadata_bytes(kind: bytes, data: bytes, budget: int) -> int:
    """Bytes a PNG metadata chunk becomes once decoded (compressed text counted inflated)."""
    sep = data.find(b"\0")
    if kind in (b"zTXt", b"iCCP") and sep >= 0:
        return sep + _inflated(data, sep + 2, budget)
    if kind == b"iTXt" and sep >= 0 and data[sep + 1:sep + 2] == b"\1":  # compressed international text
        tail = data.find(b"\0", data.find(b"\0", sep + 3) + 1)
        return len(data) if tail < 0 else tail + _inflated(data, tail + 1, budget)
    return len(data)


def check_png_chunks(path: str | Path, limit: int | None = None) -> None:
    """Refuse a PNG whose text and metadata chunks decode to more than :data:`MAX_PNG_METADATA`.

    The chunk headers are walked (seeking over image data); compressed chunks are inflated
    in 64 KiB steps only until the budget is spent, so the check costs at most the budget.

    Raises:
        InputError: ``"x.png: its text/metadata chunks hold more than 8.0 MiB; ..."``.
    """
    budget = MAX_PNG_METADATA if limit is None else int(limit)
    used = 0
    with open(path, "rb") as f:
        f.seek(8)
        while True:
            head = f.read(8)
            if len(head) < 8:
                return
            size, kind = struct.unpack(">I", head[:4])[0], head[4:]
            if kind == b"IEND":
                return
            if kind in _PNG_META:
                if size > budget - used + (1 << 16):  # raw chunk alone over the budget
                    used = budget + 1
                else:
                    used += _metadata_bytes(kind, f.read(size), budget - used)
                    f.seek(4, 1)
                if used > budget:
                    raise InputError(f"{path}: its text/metadata chunks hold more than {budget / 2**20:.1f} MiB; "
                                     "a photo's metadata is refused above that (tEXt/zTXt/iTXt/iCCP/eXIf)")
            else:
                f.seek(size + 4, 1)


def _jpeg(head: bytes, f) -> tuple[int, int] | None:
    f.seek(2)
    for _ in range(4096):  # markers before the frame header; a real file has a few dozen
        byte = f.read(1)
        while byte == b"\xff":  # fill bytes
            byte = f.read(1)
        if not byte:
            return None
        marker = byte[0]
        if marker == 0xD8 or 0xD0 <= marker <= 0xD7 or marker == 0x01:
            continue
        if marker in (0xD9, 0xDA):  # end of image or start of scan before any frame header
            return None
        seg = f.read(2)
        if len(seg) < 2:
            return None
        size = struct.unpack(">H", seg)[0]
        if marker in (0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF):
            h, w = struct.unpack(">xHH", f.read(5))
            return w, h
        if size < 2:
            return None
        f.seek(size - 2, 1)
        # the marker before the next segment
        if f.read(1) != b"\xff":
            return None
    return None


def _gif(head: bytes, f) -> tuple[int, int]:
    return struct.unpack("<HH", head[6:10])


def _bmp(head: bytes, f) -> tuple[int, int]:
    dib = struct.unpack("<I", head[14:18])[0]
    if dib == 12:
        w, h = struct.unpack("<HH", head[18:22])
    else:
        w, h = struct.unpack("<ii", head[18:26])
    return w, abs(h)


def _webp(head: bytes, f) -> tuple[int, int] | None:
    if head[8:12] != b"WEBP":
        return None
    kind = head[12:16]
    if kind == b"VP8 ":
        w, h = struct.unpack("<HH", head[26:30])
        return w & 0x3FFF, h & 0x3FFF
    if kind == b"VP8L":
        bits = struct.unpack("<I", head[21:25])[0]
        return (bits & 0x3FFF) + 1, ((bits >> 14) & 0x3FFF) + 1
    if kind == b"VP8X":
        return int.from_bytes(head[24:27], "little") + 1, int.from_bytes(head[27:30], "little") + 1
    return None


def _tiff(head: bytes, f) -> tuple[int, int] | None:
    end = "<" if head[:2] == b"II" else ">"
    ifd = struct.unpack(end + "I", head[4:8])[0]
    f.seek(ifd)
    count = struct.unpack(end + "H", f.read(2))[0]
    size = {}
    for _ in range(min(count, 1024)):
        tag, typ, _, value = struct.unpack(end + "HHI4s", f.read(12))
        if tag in (256, 257):
            size[tag] = struct.unpack(end + "H", value[:2])[0] if typ == 3 else struct.unpack(end + "I", value)[0]
    return (size[256], size[257]) if len(size) == 2 else None


def _exr(head: bytes, f) -> tuple[int, int] | None:
    i, windows = 8, []
    while i < len(head) and head[i] != 0:
        name_end = head.index(b"\0", i)
        type_end = head.index(b"\0", name_end + 1)
        size = struct.unpack("<i", head[type_end + 1:type_end + 5])[0]
        value = head[type_end + 5:type_end + 5 + size]
        if head[i:name_end] in (b"dataWindow", b"displayWindow") and head[name_end + 1:type_end] == b"box2i":
            x0, y0, x1, y1 = struct.unpack("<iiii", value[:16])
            windows.append((x1 - x0 + 1, y1 - y0 + 1))
        if size < 0:
            return None
        i = type_end + 5 + size
    if not windows:
        return None
    return max(w for w, _ in windows), max(h for _, h in windows)


_HDR_SIZE = re.compile(rb"\n([-+])([XY]) +(\d+) +([-+])([XY]) +(\d+)\s*\n")


def _hdr(head: bytes, f) -> tuple[int, int] | None:
    m = _HDR_SIZE.search(head)
    if m is None:
        return None
    first, second = (m.group(2), int(m.group(3))), (m.group(5), int(m.group(6)))
    dims = dict([first, second])
    return (dims[b"X"], dims[b"Y"]) if len(dims) == 2 else None


def _pnm(head: bytes, f) -> tuple[int, int] | None:
    if head[:2] == b"P7":
        w = re.search(rb"\nWIDTH +(\d+)", head)
        h = re.search(rb"\nHEIGHT +(\d+)", head)
        return (int(w.group(1)), int(h.group(1))) if w and h else None
    text = re.sub(rb"#[^\n]*", b" ", head[2:512])
    nums = text.split()
    return int(nums[0]), int(nums[1])


def _qoi(head: bytes, f) -> tuple[int, int]:
    return struct.unpack(">II", head[4:12])


_READERS = (
    (b"\x89PNG\r\n\x1a\n", _png),
    (b"\xff\xd8", _jpeg),
    (b"GIF87a", _gif),
    (b"GIF89a", _gif),
    (b"BM", _bmp),
    (b"RIFF", _webp),
    (b"II*\x00", _tiff),
    (b"MM\x00*", _tiff),
    (b"\x76\x2f\x31\x01", _exr),
    (b"#?RADIANCE", _hdr),
    (b"#?RGBE", _hdr),
    (b"qoif", _qoi),
    *((f"P{k}".encode(), _pnm) for k in range(1, 8)),
)


def check_image_file(path: str | Path, what: str = "an image") -> tuple[int, int] | None:
    """Refuse a missing path, a folder, or an image whose header is above the pixel limit
    (:func:`relightnet.io.limits.check_pixels`), before anything is decoded. Imports no
    torch, so the command line refuses an oversized photo at once.

    Returns:
        The header's (width, height), or None for a format :func:`header_size` does not know
        (the decoder's own limit then applies).

    Raises:
        InputError: naming ``path``.
    """
    path = Path(path)
    if not path.exists():
        if path.is_symlink():
            raise InputError(f"{path}: a symbolic link to nothing (broken or looping); expected {what}")
        raise InputError(f"{path}: no such file")
    if not path.is_file():
        raise InputError(f"{path}: is a folder or special file, not a file")
    try:
        size = header_size(path)
    except OSError as e:
        raise InputError(f"{path}: cannot read {what} ({e})") from None
    if size is not None:
        check_pixels(*size, f"{path}")
    try:
        with open(path, "rb") as f:
            png = f.read(8) == b"\x89PNG\r\n\x1a\n"
        if png:
            check_png_chunks(path)
    except OSError as e:
        raise InputError(f"{path}: cannot read {what} ({e})") from None
    return size
