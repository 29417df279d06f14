"""The trainable fast guided filter and the pooled network input of a network at half resolution."""

import pytest
import torch
from torch.nn import functional as F

from relightnet.checks import InputError, ShapeError
from relightnet.model.guided import LUMA, FastGuidedUpsample, double_to, fast_guided_upsample, pool_input
from relightnet.model.network import normalize_input
from relightnet.raster.morphology import box_filter


def _guide(b=2, c=1, h=16, w=24, seed=0):
    return torch.rand(b, c, h, w, generator=torch.Generator().manual_seed(seed), dtype=torch.float64)


@pytest.mark.parametrize("guide_channels", [1, 3])
def test_a_linear_function_of_the_guide_comes_back_exactly(guide_channels):
    """p = a · g + c at low resolution (g the pooled guide) upsamples to a · G + c: the slope is a wherever
    the guide varies (eps → 0) and the offset p − a · g is c, both constant, so bilinear upsampling keeps
    them; float64 rounding of box sums of values in [0, 1] stays far below 1e-9."""
    big = _guide(c=guide_channels)
    a = torch.tensor([2.0, -0.5, 0.25], dtype=torch.float64).view(1, 3, 1, 1)
    c = torch.tensor([0.1, 1.0, -3.0], dtype=torch.float64).view(1, 3, 1, 1)
    low = a * F.avg_pool2d(big, 2) + c
    out = fast_guided_upsample(low, big, 2, radius=1, eps=1e-14)
    torch.testing.assert_close(out, a * big + c, atol=1e-9, rtol=0)


@pytest.mark.parametrize("scale", [1, 2, 4])
def test_a_constant_guide_gives_bilinear_upsampling(scale):
    low = _guide(c=4, h=5, w=7, seed=1)
    big = torch.full((2, 1, 5 * scale, 7 * scale), 0.3, dtype=torch.float64)
    out = fast_guided_upsample(low, big, scale, radius=2, eps=1e-2)
    want = low if scale == 1 else F.interpolate(low, scale_factor=scale, mode="bilinear", align_corners=False)
    torch.testing.assert_close(out, want, atol=1e-12, rtol=0)


def test_it_is_differentiable_in_the_map_the_guide_and_eps():
    low = _guide(b=1, c=2, h=3, w=4, seed=2).requires_grad_()
    big = _guide(b=1, c=2, h=6, w=8, seed=3).requires_grad_()
    eps = torch.tensor([1e-2, 3e-2], dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda p, g, e: fast_guided_upsample(p, g, 2, 1, e), (low, big, eps))


def test_box_filter_is_the_mean_over_existing_pixels():
    x = _guide(b=1, c=1, h=4, w=5)
    out = box_filter(x, 1)
    torch.testing.assert_close(out[0, 0, 0, 0], x[0, 0, :2, :2].mean())
    torch.testing.assert_close(out[0, 0, 2, 2], x[0, 0, 1:4, 1:4].mean())
    assert box_filter(x, 0) is x


def test_bad_inputs_are_refused():
    low, big = torch.rand(1, 3, 4, 4), torch.rand(1, 1, 8, 8)
    with pytest.raises(ShapeError, match="guide"):
        fast_guided_upsample(low, big[..., :7], 2)
    with pytest.raises(ShapeError, match="guide"):
        fast_guided_upsample(low, torch.rand(1, 2, 8, 8), 2)
    with pytest.raises(InputError, match="eps"):
        fast_guided_upsample(low, big, 2, eps=0.0)
    with pytest.raises(InputError, match="scale"):
        fast_guided_upsample(low, big, 0)
    with pytest.raises(ShapeError, match="multiples of 2"):
        pool_input(torch.rand(1, 4, 7, 8), 2)


def test_the_module_starts_from_the_luminance_of_the_person():
    image, mask = torch.rand(2, 3, 16, 16), (torch.rand(2, 1, 16, 16) > 0.5).float()
    x = normalize_input(image, mask)
    up = FastGuidedUpsample(5, scale=2, eps=1e-3)
    guide = up.guide(x)
    luma = (image * torch.tensor(LUMA).view(1, 3, 1, 1)).sum(1, keepdim=True) * mask
    torch.testing.assert_close(guide, luma.expand(-1, 5, -1, -1))
    torch.testing.assert_close(up.log_eps.exp(), torch.full((5,), 1e-3))
    out = up(torch.randn(2, 5, 8, 8), x)
    assert out.shape == (2, 5, 16, 16) and out.dtype == torch.float32
    out.sum().backward()
    assert all(p.grad is not None and torch.isfinite(p.grad).all() for p in up.parameters())


def test_pooling_the_ke18_input_is_the_ke18_input_of_the_mask_weighted_mean():
    image, mask = torch.rand(2, 3, 8, 12), (torch.rand(2, 1, 8, 12) > 0.4).float()
    pooled = pool_input(normalize_input(image, mask), 2)
    m = F.avg_pool2d(mask, 2)
    mean_colour = F.avg_pool2d(image * mask, 2) / m.clamp_min(1e-8)
    torch.testing.assert_close(pooled, normalize_input(mean_colour, m))


def test_double_to_upsamples_by_two_and_crops_to_an_odd_skip():
    x = torch.rand(1, 2, 4, 3)
    even = double_to(x, torch.empty(1, 5, 8, 6))
    torch.testing.assert_close(even, F.interpolate(x, size=(8, 6), mode="bilinear", align_corners=False))
    odd = double_to(x, torch.empty(1, 5, 7, 6))
    assert odd.shape == (1, 2, 7, 6) and torch.equal(odd, even[..., :7, :])
