"""sRGB transfer functions, PNG writing and reading."""

import numpy as np
import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.color import linear_to_srgb, srgb_to_linear
from relightnet.io import read_image, to_uint8, write_image


def test_srgb_known_values_and_inverse():
    x = torch.tensor([0.0, 0.0031308, 0.18, 0.5, 1.0], dtype=torch.float64)
    y = linear_to_srgb(x)
    ref = torch.tensor([0.0, 0.0031308 * 12.92, 0.4613561295, 0.7353569831, 1.0], dtype=torch.float64)
    torch.testing.assert_close(y, ref, rtol=0, atol=1e-9)
    grid = torch.linspace(0, 1, 10001, dtype=torch.float64)
    torch.testing.assert_close(srgb_to_linear(linear_to_srgb(grid)), grid, rtol=0, atol=1e-12)
    torch.testing.assert_close(linear_to_srgb(srgb_to_linear(grid)), grid, rtol=0, atol=1e-12)
    # Both pieces meet (continuity at the breakpoints) and the curve is increasing.
    assert (linear_to_srgb(grid).diff() > 0).all()


def test_uint8_png_round_trip_is_exact(tmp_path):
    g = torch.Generator().manual_seed(0)
    img = torch.randint(0, 256, (7, 11, 3), generator=g, dtype=torch.uint8)
    path = write_image(tmp_path / "a.png", img)
    back = read_image(path)
    assert back.shape == (7, 11, 3) and back.dtype == torch.float32
    torch.testing.assert_close((back * 255).round().to(torch.uint8), img, rtol=0, atol=0)


def test_float_linear_is_srgb_encoded_and_read_back_linear(tmp_path):
    img = torch.linspace(0, 1, 64).reshape(4, 16, 1).expand(4, 16, 3).contiguous()
    path = write_image(tmp_path / "f.png", img)
    enc = read_image(path)
    torch.testing.assert_close(enc, linear_to_srgb(img), rtol=0, atol=0.5 / 255 + 1e-6)
    lin = read_image(path, linear=True)
    torch.testing.assert_close(lin, img, rtol=0, atol=0.01)
    raw = write_image(tmp_path / "raw.png", img, srgb=False)
    torch.testing.assert_close(read_image(raw), img, rtol=0, atol=0.5 / 255 + 1e-6)


def test_gray_and_out_of_range_values(tmp_path):
    img = torch.tensor([[-1.0, 0.5, 2.0]]).reshape(1, 3, 1)
    back = read_image(write_image(tmp_path / "g.png", img, srgb=False))
    assert back.shape == (1, 3, 3)  # gray repeated to RGB
    torch.testing.assert_close(back[0, :, 0], torch.tensor([0.0, 128 / 255, 1.0]))
    assert (back[..., 0] == back[..., 1]).all() and (back[..., 1] == back[..., 2]).all()
    assert to_uint8(np.zeros((2, 2, 3), np.float32)).dtype == torch.uint8


def test_write_and_read_errors(tmp_path):
    with pytest.raises(ShapeError, match="image"):
        write_image(tmp_path / "a.png", torch.zeros(4, 4, 2))
    with pytest.raises(InputError, match=r"\.png"):
        write_image(tmp_path / "a.jpg", torch.zeros(4, 4, 3))
    with pytest.raises(InputError, match="NaN"):
        write_image(tmp_path / "a.png", torch.full((4, 4, 3), float("nan")))
    with pytest.raises(InputError, match="does not exist"):
        write_image(tmp_path / "no" / "a.png", torch.zeros(4, 4, 3))
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError, match="nothing.png"):
        read_image(tmp_path / "nothing.png")
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG but not really")
    with pytest.raises(InputError, match="bad.png"):
        read_image(bad)
