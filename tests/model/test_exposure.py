import pytest
import torch

from relightnet.checks import ShapeError
from relightnet.color import luminance
from relightnet.model import Prediction, shading_map
from relightnet.model.exposure import exposure_level, exposure_scale, match_exposure, transport_level
from relightnet.pipeline.relight_image import match_exposure as pipeline_match_exposure


def _prediction(b=3, k=9, s=12, seed=0):
    g = torch.Generator().manual_seed(seed)
    transport = 0.3 * torch.randn(b, k, s, s, generator=g)
    transport[:, 0] = 1.0  # positive shading under a light with a strong l = 0 term
    light = 0.1 * torch.randn(b, k, 3, generator=g)
    light[:, 0] = torch.tensor([1.0, 2.0, 4.0])[:, None]  # the items at three exposures
    mask = torch.zeros(b, 1, s, s)
    mask[:, :, 2:10, 3:9] = 1
    return Prediction(torch.rand(b, 3, s, s, generator=g), transport, light, mask)


def _mean_luminance(shading, mask):
    return (luminance(shading.movedim(1, -1))[:, None] * mask).sum((1, 2, 3)) / mask.sum((1, 2, 3))


def test_level_is_the_mean_luminance_over_the_mask_pooled_or_per_item():
    pred = _prediction()
    s = pred.shading()
    per_item = _mean_luminance(s, pred.mask)
    torch.testing.assert_close(exposure_level(s, pred.mask, per_item=True), per_item)
    torch.testing.assert_close(exposure_level(s, pred.mask), per_item.mean())  # equal masks: the mean of items
    assert float(exposure_level(s, torch.zeros_like(pred.mask))) == 0  # empty mask: no level, no NaN


def test_scale_brings_a_level_to_another_and_is_one_where_nothing_can_be_matched():
    torch.testing.assert_close(exposure_scale(torch.tensor([2.0, 3.0]), torch.tensor([4.0, 1.0])),
                               torch.tensor([0.5, 3.0], dtype=torch.float64))
    assert float(exposure_scale(1.0, 0.0)) == 1.0  # the new light does not reach the person
    assert float(exposure_scale(0.0, 2.0)) == 1.0  # no exposure to keep
    assert exposure_scale(2.0, 4.0).dtype == torch.float64


def test_matched_light_keeps_each_items_level_per_item_and_the_batch_level_pooled():
    pred = _prediction()
    new = 0.1 * torch.randn(9, 3, generator=torch.Generator().manual_seed(1))
    new[0] = 30.0  # a light at a projected HDRI's scale
    old = _mean_luminance(pred.shading(), pred.mask)
    per_item = match_exposure(new, pred, per_item=True)
    assert per_item.shape == (3, 9, 3)
    torch.testing.assert_close(_mean_luminance(shading_map(pred.transport, per_item), pred.mask), old)
    pooled = match_exposure(new, pred)
    assert pooled.shape == new.shape
    level = _mean_luminance(shading_map(pred.transport, pooled), pred.mask)
    torch.testing.assert_close(level.mean(), old.mean())  # the batch's level (equal masks: the mean of items)
    torch.testing.assert_close(pooled / new, (pooled / new)[0, 0].expand_as(new))  # one factor: direction, colour kept


def test_pipeline_matches_exposure_with_the_models_primitive():
    assert pipeline_match_exposure is match_exposure
    pred = Prediction(torch.rand(1, 3, 4, 4), torch.ones(1, 4, 4, 4), torch.ones(1, 4, 3))
    torch.testing.assert_close(match_exposure(2 * torch.ones(4, 3), pred), torch.ones(4, 3))  # no mask: whole map
    with pytest.raises(ShapeError, match="shading"):
        exposure_level(torch.ones(1, 2, 4, 4), torch.ones(1, 1, 4, 4))


def test_closed_form_level_from_the_weighted_transport_equals_the_level_of_the_shading():
    full = _prediction()
    pred = Prediction(full.albedo[:1], full.transport[:1], full.light[:1], full.mask[:1])
    light = 0.2 * torch.randn(9, 3, generator=torch.Generator().manual_seed(2))
    light[0] = 1.5
    total = (pred.transport * pred.mask).sum((0, 2, 3), dtype=torch.float64)
    mass = float(pred.mask.sum())
    expected = float(exposure_level(shading_map(pred.transport, light), pred.mask))
    assert transport_level(total, light, mass) == pytest.approx(expected, rel=1e-5)  # float32 sums vs float64
    assert transport_level(total / mass, light) == pytest.approx(expected, rel=1e-5)  # a mean transport: mass 1
