"""The soft matte in the person's border band (guided filter on the photo)."""

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.segment.matte import SoftMatte, band_radius, border_band, soft_matte


def _disc(h=96, w=96, radius=30.3, ss=8):
    """(coverage (H, W) exact to 1/ss², photo (3, H, W)): a bright disc on a dark, coloured background."""
    y = (torch.arange(h * ss, dtype=torch.float64) + 0.5) / ss
    x = (torch.arange(w * ss, dtype=torch.float64) + 0.5) / ss
    inside = ((y[:, None] - h / 2) ** 2 + (x[None] - w / 2) ** 2 < radius ** 2).double()
    cov = inside.view(h, ss, w, ss).mean((1, 3)).float()
    fg, bg = torch.tensor([0.9, 0.8, 0.7]).view(3, 1, 1), torch.tensor([0.1, 0.3, 0.2]).view(3, 1, 1)
    return cov, cov * fg + (1 - cov) * bg


def test_matte_is_in_unit_range_and_equals_the_mask_away_from_the_band():
    cov, img = _disc()
    mask = (cov > 0.5).float()
    alpha = soft_matte(img, mask, radius=3)
    assert alpha.shape == mask.shape and alpha.dtype == torch.float32
    assert float(alpha.min()) >= 0 and float(alpha.max()) <= 1
    band = border_band(mask, 3)
    assert torch.equal(alpha[~band], mask[~band])


def test_matte_recovers_fractional_coverage_from_a_binary_mask():
    cov, img = _disc()
    mask = (cov > 0.5).float()
    band = border_band(mask, 3)
    alpha = soft_matte(img, mask, radius=3)
    hard = float((mask - cov)[band].abs().mean())
    soft = float((alpha - cov)[band].abs().mean())
    # The binary mask is off by the partial coverage of each edge pixel; the filter's local linear
    # model of the mask on the photo follows the photo's blend, the regularisation leaving a little.
    assert soft < 0.5 * hard
    assert soft < 0.08


def test_matte_of_a_soft_input_linear_in_the_photo_is_that_input():
    cov, img = _disc()
    alpha = soft_matte(img, cov, radius=3, eps=1e-5)
    band = border_band(cov, 3)
    # p = c is exactly linear in the luminance (contrast 0.58 between the two colours), so each
    # window's fit is exact but for the slope's shrink var / (var + eps): var >= ~1e-3 where c varies.
    assert float((alpha - cov)[band].abs().max()) < 0.02


def test_band_radius_scales_with_the_image():
    assert band_radius(256, 256) == 2
    assert band_radius(1866, 2808) == 11
    assert band_radius(4000, 6000) > band_radius(1000, 1500)


def test_the_module_equals_the_function():
    cov, img = _disc()
    mask = (cov > 0.5).float()
    assert torch.equal(SoftMatte(radius=3)(img, mask), soft_matte(img, mask, radius=3))
    as_bytes = soft_matte((img * 255).round().to(torch.uint8), mask, 3)
    # 8-bit rounding moves the guide by <= 1/510 against the edge's contrast 0.58: a few hundredths at most.
    assert float((as_bytes - soft_matte(img, mask, 3)).abs().max()) < 0.05


def test_an_empty_mask_stays_empty():
    _, img = _disc()
    z = torch.zeros(96, 96)
    assert torch.equal(soft_matte(img, z), z)


def test_bad_shapes_and_values_raise():
    cov, img = _disc()
    with pytest.raises(ShapeError):
        soft_matte(img[:2], cov)
    with pytest.raises(ShapeError):
        soft_matte(img, cov[:10])
    with pytest.raises(InputError):
        soft_matte(img, cov, eps=0.0)
    with pytest.raises(InputError):
        soft_matte(img, cov, radius=0)
