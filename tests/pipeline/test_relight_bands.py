"""relight_over_photo (a photo relit in bands of rows) against the whole-photo formulas on the pasted
prediction: the photo albedo, A ⊙ (T · L′), the sRGB composite over the photo."""

import pytest
import torch

from relightnet.color import linear_to_srgb, luminance, srgb_to_linear
from relightnet.io import to_uint8
from relightnet.model import NetConfig, RelightNet, photo_albedo, shading_map
from relightnet.model.exposure import match_exposure
from relightnet.model.photo_albedo import ALBEDO_FLOOR
from relightnet.pipeline import TorchPredictor, relight_over_photo
from relightnet.raster import to_channels_last
from relightnet.render import composite


def _whole(pred, image, light, detail, keep_exposure, reference=None):
    """The relight written on the whole pasted prediction at once (the reference for the bands):
    ``(relit (1, 3, H, W) linear, albedo, light used, shading T · L′)``."""
    import dataclasses

    ref = pred if reference is None else dataclasses.replace(pred, light=reference)
    before = ref.shading()
    new = match_exposure(light, ref, before) if keep_exposure else light
    albedo = photo_albedo(srgb_to_linear(image), ref, shading=before) if detail else pred.albedo
    shading = shading_map(pred.transport, new)
    return albedo * shading, albedo, new, shading


def _over(relit, mask, image):
    """(1, H, W, 3) the relit person sRGB-encoded over the photo."""
    fg = to_channels_last(linear_to_srgb(relit.clamp(0, 1)))
    return composite(fg, to_channels_last(mask), to_channels_last(image))


@pytest.fixture(scope="module")
def predict():
    torch.manual_seed(0)
    return TorchPredictor(RelightNet(NetConfig(width=8, max_width=32, light_hidden=32)).eval(), size=32)


@pytest.fixture(scope="module")
def photo():
    """A 600 × 70 photo (three bands of rows) whose person runs off its bottom edge."""
    torch.manual_seed(1)
    img = torch.rand(3, 600, 70)
    mask = torch.zeros(600, 70)
    mask[150:, 10:60] = 1
    mask[150:160, 10:60] = 0.5  # a soft edge
    return img, mask


@pytest.mark.parametrize("detail, keep_exposure, own_reference", [(True, True, False), (False, True, False),
                                                                   (True, False, True), (False, False, False)])
def test_bands_relight_as_the_whole_photo(predict, photo, detail, keep_exposure, own_reference):
    img, mask = photo
    crop = predict.crop(img, mask)
    pred = crop.pasted()
    light = torch.randn(9, 3) * 0.3 + torch.tensor([[1.0, 0.9, 0.8]] + [[0.0, 0.0, 0.0]] * 8)
    ref = torch.randn(9, 3).abs() if own_reference else None
    linear, w_albedo, w_light, w_shading = _whole(pred, img[None], light, detail, keep_exposure,
                                                  None if ref is None else ref[None])
    expected = _over(linear, pred.mask, img[None])[0]
    res = relight_over_photo(crop, img, light, detail=detail, keep_exposure=keep_exposure, reference=ref,
                             keep_albedo=True)
    torch.testing.assert_close(res.light, w_light, rtol=1e-4, atol=1e-6)
    torch.testing.assert_close(res.image, expected, rtol=1e-4, atol=1e-4)
    person = relight_over_photo(crop, img, light, detail=detail, keep_exposure=keep_exposure, reference=ref,
                                composite=False)  # the relit person alone, linear (compare's 2D path)
    torch.testing.assert_close(_over(person.image.permute(2, 0, 1)[None], pred.mask, img[None])[0], res.image,
                               rtol=0, atol=1e-6)  # the same band, composited or not
    torch.testing.assert_close(person.image, to_channels_last(linear)[0], rtol=1e-3, atol=1e-4)  # albedo's note below
    assert torch.equal(person.image[mask == 0], torch.zeros(int((mask == 0).sum()), 3))
    # The albedo is the photo divided by the shading. Where the shading's K terms cancel, the two paths'
    # float32 sums (in different orders) differ by ~K·eps·Σ|T_k L_k|, large against a small S: the
    # tolerance follows that conditioning (64 eps per unit of it) on top of assert_close's 1e-4 + 1e-4 relative.
    src = pred.light.reshape(-1, 9, 3)  # the photo is divided by its own shading, T · L̂
    cond = shading_map(pred.transport.abs(), src.abs()) / shading_map(pred.transport, src).abs().clamp_min(1e-12)
    tol = 1e-4 + (1e-4 + 64 * torch.finfo(torch.float32).eps * cond[0]) * w_albedo[0].abs()
    # Below the floor (Y(S) < floor · Ȳ) the divisor is floor · Ȳ: the albedo is inversely proportional to the
    # person's mean shading Ȳ, which the whole photo sums in float32 over its n pixels and the bands in float64,
    # so there it may differ by the float32 sum's bound n · eps relative.
    y = luminance(shading_map(pred.transport, src).movedim(1, -1))[0]
    m = pred.mask[0, 0]
    floored = y < ALBEDO_FLOOR * (y * m).sum() / m.sum()
    eps_sum = float(m.sum()) * torch.finfo(torch.float32).eps
    tol = torch.where(floored, tol + eps_sum * w_albedo[0].abs(), tol)
    assert ((res.albedo - w_albedo[0]).abs() <= tol).all()
    lit = ((w_shading.mean(1, keepdim=True) > 0).float() * pred.mask).sum() / pred.mask.sum()
    assert abs(res.lit - float(lit)) < 1e-3
    eight = relight_over_photo(crop, (img * 255).round().to(torch.uint8), light, detail=detail,
                               keep_exposure=keep_exposure, reference=ref, dtype=torch.uint8)
    assert eight.image.dtype == torch.uint8 and eight.albedo is None
    img8 = (img * 255).round()[None] / 255
    quantised = to_uint8(_over(_whole(pred, img8, light, detail, keep_exposure, None if ref is None else ref[None])[0],
                               pred.mask, img8)[0], srgb=False)
    assert (eight.image.int() - quantised.int()).abs().max() <= 1
    outside = mask == 0
    assert torch.equal(eight.image[outside], (img * 255).round().to(torch.uint8).permute(1, 2, 0)[outside])


def test_a_gray_photo_gives_a_gray_person_under_a_coloured_light(predict, photo):
    from relightnet.light import preset_light
    from relightnet.pipeline.relight_bands import is_gray

    img, mask = photo
    gray = img.mean(0, keepdim=True).expand(3, -1, -1).contiguous()
    assert is_gray(gray) and is_gray((gray * 255).round().byte()) and not is_gray(img)
    crop = predict.crop(gray, mask)
    for dtype in (torch.float32, torch.uint8):
        src = gray if dtype == torch.float32 else (gray * 255).round().byte()
        res = relight_over_photo(crop, src, preset_light("sunset"), dtype=dtype)
        levels = res.image.float() * (255 if dtype == torch.float32 else 1)
        assert (levels.amax(-1) - levels.amin(-1)).max() <= 1  # no chroma: within one level
    coloured = relight_over_photo(predict.crop(img, mask), img, preset_light("sunset"))
    spread = coloured.image.amax(-1) - coloured.image.amin(-1)
    assert float(spread[mask > 0].mean()) > 0.05  # a coloured photo keeps its colour


@pytest.mark.parametrize("dtype", [torch.float32, torch.uint8])
def test_only_the_persons_span_is_computed_and_the_photo_is_left_alone(predict, photo, dtype):
    """Pixels outside the rows and columns the mask spans are the photo's; a photo given as a view of
    channels-last pixels (as read from a file) is not written to; the span matches the mask."""
    img, mask = photo
    hwc = (img * 255).round().to(torch.uint8).permute(1, 2, 0).contiguous()
    view = hwc.permute(2, 0, 1) if dtype == torch.uint8 else hwc.float().div(255).permute(2, 0, 1)
    before = view.clone()
    crop = predict.crop(view, mask)
    assert crop.span() == (150, 600, 10, 60)
    res = relight_over_photo(crop, view, torch.tensor([[1.0, 0.9, 0.8]] + [[0.0] * 3] * 8), dtype=dtype,
                             soft_edges=True)
    assert torch.equal(view, before)
    outside = torch.ones(600, 70, dtype=torch.bool)
    outside[150:, 10:60] = False
    assert res.image.shape == (600, 70, 3) and res.image.dtype == dtype
    from relightnet.segment.matte import band_radius, border_band

    far = outside & ~border_band(mask, band_radius(600, 70))  # the soft matte may reach into its band only
    assert torch.equal(res.image[far], before.permute(1, 2, 0)[far])
    assert not torch.equal(res.image[~outside], before.permute(1, 2, 0)[~outside])


def test_the_person_alone_is_linear_float_without_a_soft_edge(predict, photo):
    """composite=False (compare's 2D path) refuses what only a composite has: uint8 levels, the soft matte."""
    from relightnet.checks import InputError

    img, mask = photo
    crop = predict.crop(img, mask)
    light = torch.tensor([[1.0, 0.9, 0.8]] + [[0.0] * 3] * 8)
    for kw in ({"dtype": torch.uint8}, {"soft_edges": True}):
        with pytest.raises(InputError, match="composite=False"):
            relight_over_photo(crop, img, light, composite=False, **kw)
