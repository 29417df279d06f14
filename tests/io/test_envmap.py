"""EXR/HDR environment maps: channel order against a hand-written EXR, round trips, errors."""

import struct

import numpy as np
import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.io import read_envmap, write_envmap
from relightnet.light.presets import preset_path


def _write_uncompressed_exr(path, rgb: np.ndarray) -> None:
    """A minimal scanline OpenEXR file (no compression, FLOAT channels B, G, R), written by hand."""
    h, w, _ = rgb.shape

    def attr(name: str, typ: str, data: bytes) -> bytes:
        return name.encode() + b"\0" + typ.encode() + b"\0" + struct.pack("<i", len(data)) + data

    names = "BGR"  # EXR stores channels sorted by name
    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in names) + b"\0"
    box = struct.pack("<4i", 0, 0, w - 1, h - 1)
    header = (
        struct.pack("<ii", 20000630, 2)
        + attr("channels", "chlist", chlist)
        + attr("compression", "compression", b"\0")
        + attr("dataWindow", "box2i", box)
        + attr("displayWindow", "box2i", box)
        + attr("lineOrder", "lineOrder", b"\0")
        + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
        + attr("screenWindowCenter", "v2f", struct.pack("<2f", 0.0, 0.0))
        + attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
        + b"\0"
    )
    chan = {"R": 0, "G": 1, "B": 2}
    chunks = []
    for y in range(h):
        data = b"".join(rgb[y, :, chan[c]].astype("<f4").tobytes() for c in names)
        chunks.append(struct.pack("<ii", y, len(data)) + data)
    offsets, pos = [], len(header) + 8 * h
    for c in chunks:
        offsets.append(pos)
        pos += len(c)
    with open(path, "wb") as f:
        f.write(header + struct.pack(f"<{h}Q", *offsets) + b"".join(chunks))


def test_channel_order_matches_hand_written_exr(tmp_path):
    h, w = 3, 5
    rgb = np.zeros((h, w, 3), np.float32)
    rgb[..., 0] = 1.0 + np.arange(w)  # R: ramp along x
    rgb[..., 1] = 100.0  # G: constant
    rgb[..., 2] = 1000.0 * (1 + np.arange(h))[:, None]  # B: ramp along y
    path = tmp_path / "known.exr"
    _write_uncompressed_exr(path, rgb)
    env = read_envmap(path)
    assert env.dtype == torch.float32 and env.shape == (h, w, 3)
    np.testing.assert_array_equal(env.numpy(), rgb)


def test_shipped_sunset_sun_is_red_and_nonnegative():
    env = read_envmap(preset_path("sunset"))
    assert env.shape == (512, 1024, 3)
    assert env.min() >= 0 and torch.isfinite(env).all()
    r, g, b = env.reshape(-1, 3)[env.sum(-1).argmax()].tolist()
    assert r > g > b  # a setting sun is orange-red
    # Up (top rows) is sky, brighter in blue than in red; the sun sits near the horizon.
    row = env.sum(-1).argmax() // env.shape[1]
    assert 0.35 * 512 < row < 0.5 * 512
    sky = env[:64].mean((0, 1))
    assert sky[2] > sky[0]


@pytest.mark.parametrize("fmt", ["float", "half"])
def test_ffmpeg_written_float_and_half_exr(tmp_path, fmt):
    import av

    rng = np.random.default_rng(1)
    a = rng.random((4, 6, 3)).astype(np.float32) * 10
    ctx = av.CodecContext.create("exr", "w")
    ctx.width, ctx.height, ctx.pix_fmt, ctx.options = 6, 4, "gbrpf32le", {"format": fmt}
    frame = av.VideoFrame.from_ndarray(a, format="gbrpf32le")
    (tmp_path / "a.exr").write_bytes(b"".join(bytes(p) for p in list(ctx.encode(frame)) + list(ctx.encode(None))))
    env = read_envmap(tmp_path / "a.exr").numpy()
    np.testing.assert_allclose(env, a, rtol=1e-3 if fmt == "half" else 0, atol=0)


def test_exr_round_trip_is_lossless_and_clamps_on_read(tmp_path):
    g = torch.Generator().manual_seed(0)
    env = torch.randn(8, 16, 3, generator=g) * 100
    path = write_envmap(tmp_path / "x.exr", env)
    back = read_envmap(path)
    torch.testing.assert_close(back, env.clamp_min(0), rtol=0, atol=0)


def test_hdr_round_trip_is_rgbe_precise(tmp_path):
    g = torch.Generator().manual_seed(0)
    env = torch.rand(8, 16, 3, generator=g) * 50 + 0.1
    back = read_envmap(write_envmap(tmp_path / "x.hdr", env))
    rel = ((back - env).abs() / env.amax(-1, keepdim=True)).max()
    assert rel < 0.01


def test_read_errors_name_the_file(tmp_path):
    missing = tmp_path / "missing.exr"
    with pytest.raises(InputError, match="missing.exr"):
        read_envmap(missing)
    garbage = tmp_path / "garbage.exr"
    garbage.write_bytes(b"this is not an image" * 10)
    with pytest.raises(InputError, match="garbage.exr"):
        read_envmap(garbage)
    from relightnet.io import write_image

    png = write_image(tmp_path / "ldr.png", torch.zeros(4, 4, 3))
    with pytest.raises(InputError, match="ldr.png.*not an HDR"):
        read_envmap(png)
    with pytest.raises(InputError, match="folder"):
        read_envmap(tmp_path)


def test_write_errors(tmp_path):
    with pytest.raises(InputError, match=r"\.exr or \.hdr"):
        write_envmap(tmp_path / "x.png", torch.zeros(2, 4, 3))
    with pytest.raises(ShapeError, match="env"):
        write_envmap(tmp_path / "x.exr", torch.zeros(2, 4))
    with pytest.raises(InputError, match="NaN"):
        write_envmap(tmp_path / "x.exr", torch.full((2, 4, 3), float("nan")))
    assert list(tmp_path.iterdir()) == []
