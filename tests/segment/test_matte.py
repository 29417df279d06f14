"""The soft matte in the person's border band (guided filter on the photo)."""

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.segment.matte import SoftMatte, band_radius, border_band, edge_matte, soft_composite, soft_matte


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


def _linear_disc(h=96, w=96, radius=30.3, ss=8):
    """(coverage, photo (3, H, W) sRGB, F, B): a disc blended with its background in linear light."""
    from relightnet.color import linear_to_srgb

    cov, _ = _disc(h, w, radius, ss)
    fg, bg = torch.tensor([0.6, 0.35, 0.2]).view(3, 1, 1), torch.tensor([0.05, 0.2, 0.1]).view(3, 1, 1)
    return cov, linear_to_srgb(cov * fg + (1 - cov) * bg), fg, bg


def _hard(photo, mask, gain):
    """The binary composite relight_over_photo makes: the photo times a gain (linear) inside the mask."""
    from relightnet.color import linear_to_srgb, srgb_to_linear

    relit = linear_to_srgb((srgb_to_linear(photo) * gain.view(3, 1, 1)).clamp(0, 1))
    return torch.where(mask > 0.5, relit, photo).permute(1, 2, 0).contiguous()


def test_soft_composite_relights_the_persons_share_of_each_border_pixel():
    from relightnet.color import srgb_to_linear

    cov, photo, fg, bg = _linear_disc()
    mask = (cov > 0.5).float()
    gain = torch.tensor([0.5, 0.8, 1.3])
    matte = edge_matte(photo, mask, radius=3)
    hard = _hard(photo, mask, gain)
    soft = soft_composite(hard.clone(), matte)
    truth = (cov * gain.view(3, 1, 1) * fg + (1 - cov) * bg).permute(1, 2, 0)
    band = border_band(mask, 3)
    err_hard = (srgb_to_linear(hard) - truth).abs().mean(-1)
    err_soft = (srgb_to_linear(soft) - truth).abs().mean(-1)
    # The binary paste relights the background share of the inner edge pixels and leaves the outer
    # ones unrelit; the soft composite relights the person's share only, up to the alpha's error
    # (a few hundredths, a quarter of the binary mask's on the pixels the edge covers in part).
    part = (cov > 0) & (cov < 1)
    assert float(err_soft[part].mean()) < 0.35 * float(err_hard[part].mean())
    assert float(err_soft[band].mean()) < 0.6 * float(err_hard[band].mean())
    assert torch.equal(soft[~band], hard[~band])


def test_soft_composite_of_a_light_that_changes_nothing_is_the_photo():
    cov, photo, _, _ = _linear_disc()
    mask = (cov > 0.5).float()
    same = soft_composite(_hard(photo, mask, torch.ones(3)), edge_matte(photo, mask, radius=3))
    # photo + (G - 1)·αF with G = 1 to float32 rounding of the sRGB round trip
    torch.testing.assert_close(same, photo.permute(1, 2, 0), rtol=0, atol=1e-5)


def test_soft_composite_in_bytes_is_within_one_level_of_floats():
    cov, photo, _, _ = _linear_disc()
    mask = (cov > 0.5).float()
    gain = torch.tensor([1.4, 1.0, 0.6])
    matte = edge_matte(photo, mask, radius=3)
    hard = _hard(photo, mask, gain)
    floats = soft_composite(hard.clone(), matte)
    as_bytes = soft_composite(hard.mul(255).round().to(torch.uint8), matte)
    # the gain is read from bytes rounded by 1/2 level; the person's share αF <= the pixel bounds
    # its error by that, plus the final rounding's 1/2 level
    assert float((as_bytes.float() - floats * 255).abs().max()) <= 1.0 + 1e-3


def test_edge_matte_of_a_mask_without_outline_is_none_and_leaves_the_composite():
    _, img = _disc()
    assert edge_matte(img, torch.zeros(96, 96)) is None
    assert edge_matte(img, torch.ones(96, 96)) is None
    out = torch.rand(96, 96, 3)
    assert soft_composite(out, None) is out


def test_border_band_is_the_pixels_near_both_sides():
    mask = torch.zeros(20, 20)
    mask[5:15, 5:15] = 1
    band = border_band(mask, 2)
    expect = torch.zeros(20, 20, dtype=torch.bool)
    expect[3:17, 3:17] = True
    expect[7:13, 7:13] = False
    assert torch.equal(band, expect)
    edge = torch.zeros(20, 20)
    edge[:, :10] = 1  # the image's border is neither person nor background
    assert not border_band(edge, 2)[:, :7].any() and border_band(edge, 2)[:, 8:12].all()
