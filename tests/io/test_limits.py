"""Size limits before decoding: header probing, the pixel limit, .npy/.npz byte checks, --max-pixels."""

import struct

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.cli import main
from relightnet.io import read_image, read_video, write_image
from relightnet.io.arrays import read_npy, read_npz
from relightnet.io.limits import check_pixels, max_pixels
from relightnet.io.probe import header_size


def _png_header(w, h):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "fuzz"))
    from corpus_media import png_header_only

    return png_header_only(w, h)


def test_header_sizes_of_real_files(tmp_path):
    import av

    from relightnet.io import VideoWriter, write_envmap
    from relightnet.io.image import _encode

    img = np.zeros((24, 40, 3), np.uint8)
    write_image(tmp_path / "a.png", img)
    assert header_size(tmp_path / "a.png") == (40, 24)
    (tmp_path / "a.jpg").write_bytes(_encode("mjpeg", av.VideoFrame.from_ndarray(img, "rgb24").reformat(
        format="yuvj420p")))
    assert header_size(tmp_path / "a.jpg") == (40, 24)
    for s in (".exr", ".hdr"):
        write_envmap(tmp_path / f"e{s}", np.ones((8, 16, 3), np.float32))
        assert header_size(tmp_path / f"e{s}") == (16, 8)
    (tmp_path / "g.gif").write_bytes(b"GIF89a" + struct.pack("<HH", 300, 200) + bytes(20))
    (tmp_path / "p.ppm").write_bytes(b"P6\n# comment\n300 200\n255\n" + bytes(10))
    assert header_size(tmp_path / "g.gif") == header_size(tmp_path / "p.ppm") == (300, 200)
    with VideoWriter(tmp_path / "v.mkv", fps=5) as w:
        w.write(img)
    assert header_size(tmp_path / "v.mkv") is None  # not a still image: FFmpeg's own checks apply


def test_oversized_images_are_refused_before_decoding(tmp_path, monkeypatch):
    (tmp_path / "big.png").write_bytes(_png_header(12000, 12000))
    with pytest.raises(InputError, match=r"big.png: 12000x12000 pixels \(144.0 MP\) is above the limit of 12.5 MP"):
        read_image(tmp_path / "big.png")
    (tmp_path / "zero.png").write_bytes(_png_header(0, 5))
    with pytest.raises(InputError, match="expected a positive size"):
        read_image(tmp_path / "zero.png")
    # The limit is the environment's (what --max-pixels sets): a small image above a small limit is refused,
    # in the header check or, for a video, from the container header.
    write_image(tmp_path / "ok.png", np.zeros((20, 30, 3), np.uint8))
    monkeypatch.setenv("RELIGHTNET_MAX_PIXELS", "500")
    assert max_pixels() == 500
    with pytest.raises(InputError, match="30x20 pixels"):
        read_image(tmp_path / "ok.png")
    from relightnet.io import VideoWriter

    monkeypatch.delenv("RELIGHTNET_MAX_PIXELS")
    with VideoWriter(tmp_path / "v.mkv", fps=5) as w:
        w.write(np.zeros((20, 30, 3), np.uint8))
    monkeypatch.setenv("RELIGHTNET_MAX_PIXELS", "500")
    with pytest.raises(InputError, match=r"v.mkv: .*frames above 0.0 MP are refused \(--max-pixels"):
        list(read_video(tmp_path / "v.mkv"))
    monkeypatch.setenv("RELIGHTNET_MAX_PIXELS", "lots")
    with pytest.raises(InputError, match="RELIGHTNET_MAX_PIXELS=lots: expected a positive number"):
        check_pixels(1, 1, "x")


def test_max_pixels_option(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("RELIGHTNET_MAX_PIXELS", raising=False)
    (tmp_path / "big.png").write_bytes(_png_header(9000, 8000))
    assert main(["relight-image", str(tmp_path / "big.png"), "--light", "studio", "--out",
                 str(tmp_path / "o.png")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "9000x8000 pixels (72.0 MP) is above the limit" in err and "--max-pixels" in err
    # Raised, the header passes and the (truncated) file fails in the decoder instead, still one line.
    assert main(["relight-image", str(tmp_path / "big.png"), "--light", "studio", "--out", str(tmp_path / "o.png"),
                 "--max-pixels", "80000000"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "above the limit" not in err and not (tmp_path / "o.png").exists()
    monkeypatch.delenv("RELIGHTNET_MAX_PIXELS", raising=False)


def test_npy_headers_are_checked_against_the_data(tmp_path, monkeypatch):
    np.save(tmp_path / "a.npy", np.arange(6.0).reshape(2, 3))
    np.testing.assert_array_equal(read_npy(tmp_path / "a.npy"), np.arange(6.0).reshape(2, 3))
    # The header says 10^13 numbers (80 TB) over 48 bytes of data: refused without allocating.
    lie = (tmp_path / "a.npy").read_bytes().replace(b"'shape': (2, 3), ", b"'shape': (10000000000000,), ", 1)
    (tmp_path / "lie.npy").write_bytes(lie)
    with pytest.raises(InputError, match="but the file holds"):
        read_npy(tmp_path / "lie.npy")
    np.save(tmp_path / "o.npy", np.array([object()], dtype=object), allow_pickle=True)
    with pytest.raises(InputError, match="not read"):
        read_npy(tmp_path / "o.npy")
    np.savez_compressed(tmp_path / "z.npz", a=np.zeros(1 << 20))
    assert read_npz(tmp_path / "z.npz")["a"].shape == (1 << 20,)
    monkeypatch.setenv("RELIGHTNET_MAX_ARRAY_BYTES", str(1 << 20))
    with pytest.raises(InputError, match="above the limit"):
        read_npz(tmp_path / "z.npz")  # 8 MiB from a few KB of zeros


def test_a_video_that_decodes_to_far_more_than_its_file_is_refused(tmp_path, monkeypatch):
    """A GIF of 2,000 one-pixel frames on a 2000² screen (46 KB, 8·10⁹ pixels of frames) is refused before
    its first frame is used, by every video reader; below the free floor or with the limit raised it reads."""
    import sys
    from pathlib import Path

    from relightnet.io import count_frames
    from relightnet.io.limits import EXPANSION_FREE_FRAMES, check_video_expansion

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "fuzz"))
    from resource_media import gif

    sys.path.pop(0)
    monkeypatch.delenv("RELIGHTNET_MAX_PIXELS", raising=False)  # the default limit (another test's --max-pixels set it)
    bomb = tmp_path / "bomb.gif"
    bomb.write_bytes(gif(2000, 2000, 2000))
    for read in (count_frames, lambda p: next(iter(read_video(p)))):
        with pytest.raises(InputError, match=r"bomb.gif: 2000 frames of 2000x2000 from 46 KB .*pixels per byte"):
            read(bomb)
    few = tmp_path / "few.gif"
    few.write_bytes(gif(2000, 2000, 3))  # 12 MP of frames from 129 bytes: under the free floor
    assert count_frames(few) == 3 and next(iter(read_video(few))).shape == (2000, 2000, 3)
    monkeypatch.setenv("RELIGHTNET_MAX_PIXELS_PER_BYTE", str(10**6))
    assert count_frames(bomb) == 2000
    check_video_expansion(EXPANSION_FREE_FRAMES, 5000, 2500, 1, "f")  # at the floor: never refused
    with pytest.raises(InputError, match="f: 11 frames"):
        check_video_expansion(EXPANSION_FREE_FRAMES + 1, 5000, 2500, 1, "f")


def test_an_image_played_as_a_video_is_checked_from_its_header(tmp_path, monkeypatch):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "fuzz"))
    from resource_media import gif

    sys.path.pop(0)
    monkeypatch.delenv("RELIGHTNET_MAX_PIXELS", raising=False)
    (tmp_path / "screen.gif").write_bytes(gif(65535, 65535, 2))
    with pytest.raises(InputError, match=r"screen.gif: 65535x65535 pixels .* above the limit"):
        next(iter(read_video(tmp_path / "screen.gif")))
