import math

import pytest
import torch

from relightnet.checks import ShapeError
from relightnet.color import LUMA
from relightnet.model import Prediction, photo_albedo, shading_map
from relightnet.model.photo_albedo import (
    ALBEDO_FLOOR,
    CHROMA_FULL,
    CHROMA_RANGE,
    person_mean_shading,
    photo_albedo_rows,
)

LUMA_T = torch.tensor(LUMA)


def _chromaticity(x: torch.Tensor) -> torch.Tensor:
    return x[:, :2] / x.sum(1, keepdim=True)


def test_photo_albedo_divides_the_photo_by_the_shading():
    g = torch.Generator().manual_seed(0)
    transport = torch.rand(2, 9, 16, 16, generator=g)
    transport[:, 0] += 0.5  # a positive DC term: positive shading under a positive light
    light = torch.zeros(2, 9, 3)
    light[:, 0] = 1.0
    albedo = torch.rand(2, 3, 16, 16, generator=g) * 0.8 + 0.1
    photo = albedo * shading_map(transport, light)
    cnn = torch.full_like(albedo, 0.5)  # the CNN's (wrong) albedo is not used where there is shading
    pred = Prediction(albedo=cnn, transport=transport, light=light, mask=torch.ones(2, 1, 16, 16))
    torch.testing.assert_close(photo_albedo(photo, pred), albedo)
    # No shading to divide by (dark or negative): the CNN's albedo's luminance, in the photo's colour.
    dark = Prediction(albedo=cnn, transport=transport * 0 - 1, light=light, mask=torch.ones(2, 1, 16, 16))
    out = photo_albedo(photo, dark)
    torch.testing.assert_close((out * LUMA_T.view(1, 3, 1, 1)).sum(1), torch.full((2, 16, 16), 0.5))
    torch.testing.assert_close(_chromaticity(out), _chromaticity(photo), atol=2e-3, rtol=0)
    black = photo_albedo(torch.zeros_like(photo), dark)  # no colour to take: the CNN's own
    torch.testing.assert_close(black, cnn)
    with pytest.raises(ShapeError):
        photo_albedo(photo[:, :, :8], pred)


def test_strong_coloured_shading_divides_per_channel():
    """Above CHROMA_FULL of the mean and within CHROMA_RANGE of the person's tint: A = I / S exactly."""
    tint = torch.tensor([1.2, 1.0, 0.7]).view(1, 3, 1, 1)
    level = torch.linspace(CHROMA_FULL, 2.0, 64).view(1, 1, 8, 8)
    wobble = torch.exp(0.6 * CHROMA_RANGE * torch.sin(torch.arange(64.0)).view(1, 1, 8, 8) * torch.tensor(
        [1.0, -1.0, 0.5]).view(1, 3, 1, 1))
    shading = level * tint * wobble
    shading = shading / (shading * LUMA_T.view(1, 3, 1, 1)).sum(1, keepdim=True) * level
    mean = (tint / float(tint.flatten() @ LUMA_T))  # mean luminance 1: every pixel is ≥ CHROMA_FULL of it
    photo = torch.rand(1, 3, 8, 8, generator=torch.Generator().manual_seed(1)) * shading
    out = photo_albedo_rows(photo, shading, torch.zeros_like(photo), mean)
    torch.testing.assert_close(out, photo / shading)


def test_weak_shading_does_not_invent_colour():
    """Weak shading with a wild colour (one channel near zero): the albedo keeps the photo's colour
    divided by the person's tint, not by the shading's colour."""
    mean = torch.tensor([1.0, 1.0, 1.0]).view(1, 3, 1, 1)  # white: the tint divides nothing
    level = torch.linspace(ALBEDO_FLOOR, 0.9 * ALBEDO_FLOOR + 0.1 * CHROMA_FULL, 16).view(1, 1, 4, 4)
    shading = level * torch.tensor([1.6, 0.05, 1.6]).view(1, 3, 1, 1)  # magenta: per channel, green × 20
    shading = shading / (shading * LUMA_T.view(1, 3, 1, 1)).sum(1, keepdim=True) * level
    photo = torch.full((1, 3, 4, 4), 0.02)  # a gray photo
    out = photo_albedo_rows(photo, shading, torch.zeros_like(photo), mean)
    per_channel = photo / shading
    # The per-channel ratio is far from gray; the bounded one stays near it (the divisor's colour moves
    # at most w_c · CHROMA_RANGE off the tint, w_c ≤ 0.1 here).
    gray = torch.full_like(_chromaticity(out), 1 / 3)
    assert float((_chromaticity(per_channel) - gray).abs().max()) > 0.3
    bound = math.exp(0.1 * 2 * CHROMA_RANGE) - 1  # the most one channel's ratio can move relative to another
    assert float((_chromaticity(out) - gray).abs().max()) < bound / 3 + 1e-6


def test_tint_of_the_light_divides_out_where_the_shading_is_weak():
    """A warm light's tint is removed from the albedo everywhere (a white photo under it is white albedo)."""
    tint = torch.tensor([1.3, 1.0, 0.6]).view(1, 3, 1, 1)
    mean = tint / float(tint.flatten() @ LUMA_T)
    level = torch.linspace(0.02, 1.5, 25).view(1, 1, 5, 5)
    shading = level * mean * torch.tensor([1.0, 3.0, 0.2]).view(1, 3, 1, 1) ** (level < CHROMA_FULL).float()
    shading = shading / (shading * LUMA_T.view(1, 3, 1, 1)).sum(1, keepdim=True) * level
    photo = level * mean  # the truth: a white albedo under the tinted light (the shading's colour is wrong where weak)
    out = photo_albedo_rows(photo, shading, torch.zeros_like(photo), mean)
    chroma = _chromaticity(out)
    weak = (level <= ALBEDO_FLOOR).expand_as(chroma)
    assert float((chroma[weak] - 1 / 3).abs().max()) < 1e-5
    assert float((chroma - 1 / 3).abs().max()) < 0.35  # bounded everywhere; the per-channel ratio reaches 0.6


def test_rows_and_whole_agree_and_the_mean_is_the_masked_mean():
    g = torch.Generator().manual_seed(2)
    shading = torch.rand(1, 3, 600, 20, generator=g) * 2 - 0.2
    mask = (torch.rand(1, 1, 600, 20, generator=g) > 0.3).float()
    pred = Prediction(albedo=torch.rand(1, 3, 600, 20, generator=g), transport=torch.zeros(1, 9, 600, 20),
                      light=torch.zeros(1, 9, 3), mask=mask)
    photo = torch.rand(1, 3, 600, 20, generator=g)
    whole = photo_albedo_rows(photo, shading, pred.albedo, person_mean_shading(shading, mask))
    torch.testing.assert_close(photo_albedo(photo, pred, shading=shading), whole)
    assert bool((whole >= 0).all())
    torch.testing.assert_close(person_mean_shading(shading, mask)[0, :, 0, 0],
                               shading[0][:, mask[0, 0] > 0].mean(1))
