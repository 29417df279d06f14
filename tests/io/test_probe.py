"""relightnet.io.probe: image sizes from the headers of real files of every known format, None otherwise."""

import numpy as np
import pytest
import torch
from PIL import Image

from relightnet.io import write_envmap
from relightnet.io.probe import header_size


@pytest.mark.parametrize("fmt, suffix", [("PNG", ".png"), ("JPEG", ".jpg"), ("GIF", ".gif"), ("BMP", ".bmp"),
                                         ("WEBP", ".webp"), ("TIFF", ".tif"), ("PPM", ".ppm")])
def test_still_image_formats(tmp_path, fmt, suffix):
    path = tmp_path / f"img{suffix}"
    Image.fromarray(np.zeros((37, 53, 3), np.uint8)).save(path, format=fmt)
    assert header_size(path) == (53, 37)  # (width, height)


@pytest.mark.parametrize("suffix", [".exr", ".hdr"])
def test_hdr_formats(tmp_path, suffix):
    path = write_envmap(tmp_path / f"env{suffix}", torch.rand(16, 32, 3))
    assert header_size(path) == (32, 16)


def test_unknown_or_damaged_headers_give_none(tmp_path):
    (tmp_path / "a.txt").write_text("hello")
    assert header_size(tmp_path / "a.txt") is None
    Image.fromarray(np.zeros((8, 8, 3), np.uint8)).save(tmp_path / "b.jpg")
    (tmp_path / "cut.jpg").write_bytes((tmp_path / "b.jpg").read_bytes()[:20])  # markers cut before the frame
    assert header_size(tmp_path / "cut.jpg") is None
    (tmp_path / "empty.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    assert header_size(tmp_path / "empty.png") is None


def test_check_image_file_refuses_before_decoding(tmp_path, monkeypatch):
    from relightnet.errors import InputError
    from relightnet.io.probe import check_image_file

    small = tmp_path / "s.png"
    Image.fromarray(np.zeros((6, 8, 3), np.uint8)).save(small)
    assert check_image_file(small) == (8, 6)  # within the limit: its size
    monkeypatch.setenv("RELIGHTNET_MAX_PIXELS", "40")
    with pytest.raises(InputError, match=r"s.png: 8x6 pixels .* above the limit"):
        check_image_file(small)
    with pytest.raises(InputError, match="no such file"):
        check_image_file(tmp_path / "none.png")
    with pytest.raises(InputError, match="is a folder"):
        check_image_file(tmp_path)
    unknown = tmp_path / "u.bin"
    unknown.write_bytes(b"not an image header")
    assert check_image_file(unknown) is None  # unknown format: left to the decoder's own limit


def test_png_text_chunks_are_capped_before_decoding(tmp_path):
    """zTXt/iTXt/iCCP chunks count inflated (only up to the cap); a photo with small metadata still reads."""
    import struct
    import zlib

    from relightnet.checks import InputError
    from relightnet.io import read_image
    from relightnet.io.probe import MAX_PNG_METADATA, check_png_chunks

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    def png(extra):
        raw = zlib.compress(b"".join(b"\x00" + bytes(48) for _ in range(16)))
        return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 16, 16, 8, 2, 0, 0, 0)) + extra
                + chunk(b"IDAT", raw) + chunk(b"IEND", b""))

    small = chunk(b"tEXt", b"Comment\x00hello") + chunk(b"zTXt", b"Title\x00\x00" + zlib.compress(b"x" * 1000))
    (tmp_path / "ok.png").write_bytes(png(small))
    check_png_chunks(tmp_path / "ok.png")
    assert tuple(read_image(tmp_path / "ok.png").shape) == (16, 16, 3)
    bomb = zlib.compress(bytes(MAX_PNG_METADATA + 1), 9)
    assert len(bomb) < MAX_PNG_METADATA // 100
    for kind, body in ((b"zTXt", b"C\x00\x00" + bomb), (b"iTXt", b"C\x00\x01\x00en\x00\x00" + bomb),
                       (b"iCCP", b"icc\x00\x00" + bomb), (b"tEXt", b"C\x00" + bytes(MAX_PNG_METADATA + 1))):
        (tmp_path / "bomb.png").write_bytes(png(chunk(kind, body)))
        with pytest.raises(InputError, match="bomb.png: its text/metadata chunks hold more than 8.0 MiB"):
            read_image(tmp_path / "bomb.png")
    # many chunks each under the cap add up
    half = chunk(b"zTXt", b"C\x00\x00" + zlib.compress(bytes(MAX_PNG_METADATA // 2 + 10)))
    (tmp_path / "bomb.png").write_bytes(png(half * 2))
    with pytest.raises(InputError, match="more than"):
        check_png_chunks(tmp_path / "bomb.png")
