"""Optical flow (OpenCV's DIS) both ways: the motion found, unreliable where the frames disagree, sampling along it."""

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.segment.flow import backward_flow, gray_u8, sample_along


def _texture(h=96, w=128, seed=0):
    """A smooth random texture (gray, float in [0, 1]) that optical flow can follow."""
    g = torch.Generator().manual_seed(seed)
    x = torch.rand(1, 1, h // 8, w // 8, generator=g)
    return torch.nn.functional.interpolate(x, size=(h, w), mode="bicubic", align_corners=False)[0, 0].clamp(0, 1)


def test_a_shift_is_found_and_trusted():
    prev = _texture(112, 144)
    cur = torch.roll(prev, shifts=(2, 3), dims=(0, 1))  # moved 3 px right and 2 px down
    f = backward_flow(prev[8:-8, 8:-8], cur[8:-8, 8:-8])
    inner = (slice(16, -16), slice(16, -16))
    assert f.flow.shape == (96, 128, 2) and f.reliability.shape == (96, 128)
    np.testing.assert_allclose(np.median(f.flow[inner], axis=(0, 1)), [-3, -2], atol=0.25)
    assert np.median(f.reliability[inner]) > 0.8 and f.reliability.min() >= 0 and f.reliability.max() <= 1


def test_a_change_the_flow_cannot_explain_is_not_trusted():
    prev = _texture()
    cur = prev.clone()
    cur[30:60, 40:80] = 1 - cur[30:60, 40:80]  # something else appears there
    f = backward_flow(prev, cur)
    assert f.reliability[38:52, 50:70].mean() < 0.3
    assert f.reliability[70:, :].mean() > 0.8  # the rest is still and trusted


def test_inputs():
    rgb = torch.rand(3, 20, 30)
    assert gray_u8(rgb).shape == (20, 30) and gray_u8(rgb).dtype == np.uint8
    assert np.array_equal(gray_u8(torch.full((4, 5), 0.5)), np.full((4, 5), 128, np.uint8))
    with pytest.raises(InputError, match="differ in size"):
        backward_flow(torch.rand(20, 30), torch.rand(20, 31))
    with pytest.raises(InputError, match="at least 8"):
        backward_flow(torch.rand(4, 30), torch.rand(4, 30))


def test_sample_along_reads_pixel_positions():
    x = torch.arange(12.0).view(1, 1, 3, 4)
    u, v = torch.meshgrid(torch.arange(4.0), torch.arange(3.0), indexing="xy")
    same = torch.stack([u, v], -1)
    torch.testing.assert_close(sample_along(x, same), x)
    right = sample_along(x, same + torch.tensor([1.0, 0.0]))  # each pixel reads its right neighbour
    torch.testing.assert_close(right[..., :3], x[..., 1:])
    assert (right[..., 3] < x[..., 3]).all()  # past the edge: zeros blended in


def test_warp_back_reads_the_previous_frame_along_the_flow():
    from relightnet.segment.flow import warp_back

    x = np.arange(20, dtype=np.float32).reshape(4, 5)
    flow = np.zeros((2, 3, 2), np.float32)
    flow[..., 0] = 1.0  # each pixel was one to the right
    np.testing.assert_array_equal(warp_back(x, flow, origin=(1, 1)), x[1:3, 2:5])
    flow[..., 0] = 10.0  # outside: the border repeated, or zero
    np.testing.assert_array_equal(warp_back(x, flow), np.stack([x[:2, 4]] * 3, 1))
    assert not warp_back(x, flow, zero_outside=True).any()
