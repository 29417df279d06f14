"""The capture's metrics on small arrays of known answers."""

import math

import numpy as np
import pytest
import torch

from relightnet.capture.metrics import (
    HIDDEN_PARTS,
    albedo_error,
    light_invariance,
    person_psnr,
    person_ssim,
    seen_share,
    silhouette_iou,
    surface_texels,
)
from relightnet.checks import InputError, ShapeError
from relightnet.data.textures import UVAtlas


def _tex(seed=0, s=8):
    return torch.rand(s, s, 3, generator=torch.Generator().manual_seed(seed)) * 0.8 + 0.1


def test_albedo_error_ignores_exposure_and_measures_the_rest():
    truth, w = _tex(), torch.ones(8, 8, dtype=torch.bool)
    assert albedo_error(2 * truth, truth, w) == pytest.approx(0, abs=1e-12)
    # ±0.1 around a truth of 1: the best scale is 1/1.01, the relative error 0.1/√1.01
    one = torch.ones(8, 8, 3, dtype=torch.float64)
    d = 0.1 * torch.tensor([1.0, -1.0], dtype=torch.float64).repeat(32).reshape(8, 8, 1)
    assert albedo_error(one + d, one, w) == pytest.approx(0.1 / math.sqrt(1.01), rel=1e-9)
    # the weight chooses the texels: a wrong half not weighted does not count
    bad = truth.clone()
    bad[4:] = 0.5
    half = torch.zeros(8, 8)
    half[:4] = 1.0
    assert albedo_error(bad, truth, half) == pytest.approx(0, abs=1e-12)
    assert albedo_error(bad, truth, w) > 0.05
    assert albedo_error(torch.zeros(8, 8, 3), truth, w) == 1.0


def test_light_invariance_is_0_for_a_delit_capture_and_1_for_raw_colours():
    a, w = _tex(1), torch.ones(8, 8, dtype=torch.bool)
    raw_a, raw_b = a * torch.tensor([1.0, 0.8, 0.6]), a * torch.linspace(0.3, 1.2, 64).reshape(8, 8, 1)
    assert light_invariance(a, 3 * a, raw_a, raw_b, w) == pytest.approx(0, abs=1e-6)
    assert light_invariance(raw_a, 0.5 * raw_b, raw_a, raw_b, w) == pytest.approx(1, rel=1e-12)
    # texels alternate 1, 2 under light a and 2, 1 under b; the capture keeps 1, 1.5 and 1.5, 1: the
    # same RMS in each pair, so ‖â − b̂‖ / ‖r̂_a − r̂_b‖ = (0.5 / √1.625) / (1 / √2.5)
    alt = torch.tensor([0.0, 1.0], dtype=torch.float64).repeat(32).reshape(8, 8, 1).expand(8, 8, 3)
    got = light_invariance(1 + 0.5 * alt, 1.5 - 0.5 * alt, 1 + alt, 2 - alt, w)
    assert got == pytest.approx(0.5 * math.sqrt(2.5 / 1.625), rel=1e-12)
    with pytest.raises(InputError, match="scale"):
        light_invariance(a, a, raw_a, 2 * raw_a, w)


def test_metrics_refuse_bad_shapes_and_weights():
    t, w = _tex(), torch.ones(8, 8)
    with pytest.raises(ShapeError, match="truth"):
        albedo_error(t, t[:4], w)
    with pytest.raises(ShapeError, match="tex"):
        albedo_error(t[..., :2], t, w)
    with pytest.raises(ShapeError, match="weight"):
        albedo_error(t, t, w[:4])
    with pytest.raises(InputError, match="weight"):
        albedo_error(t, t, torch.zeros(8, 8))
    with pytest.raises(InputError, match="weight"):
        albedo_error(t, t, -w)
    with pytest.raises(ShapeError, match="raw_b"):
        light_invariance(t, t, t, t[None], w)
    with pytest.raises(InputError, match="expected a tensor"):
        albedo_error([[0.0]], t, w)


def _atlas():
    """A 4² atlas: texels 0–11 on islands, 12–15 padding copying texel 0; texel 5 on the tongue."""
    from relightnet.body.albedo import ANNY_PARTS

    parts = np.zeros(16, dtype=np.int64)
    parts[5] = ANNY_PARTS.index("tongue")
    src = np.arange(16)
    src[12:] = 0
    z = np.zeros((16, 3))
    return UVAtlas(4, np.arange(16), z.astype(np.int64), z.astype(np.float32), z.astype(np.float32),
                   np.arange(16), parts, src)


def test_seen_share_counts_the_visible_surface_only():
    atlas = _atlas()
    surf = surface_texels(atlas)
    assert surf.shape == (4, 4) and int(surf.sum()) == 11 and not surf.flatten()[5] and not surf[3].any()
    seen = torch.zeros(4, 4, dtype=torch.bool)
    seen[3] = True  # padding only
    seen.view(-1)[5] = True  # the tongue
    assert seen_share(seen, atlas) == 0.0
    seen.view(-1)[:5] = True
    assert seen_share(seen, atlas) == pytest.approx(5 / 11)
    assert seen_share(torch.ones(4, 4), atlas) == 1.0
    with pytest.raises(ShapeError, match="seen"):
        seen_share(torch.ones(8, 8), atlas)
    assert "tongue" in HIDDEN_PARTS and "eye_front.L" not in HIDDEN_PARTS


def test_seen_share_of_the_real_atlas(anny_body):
    from relightnet.data.textures import uv_atlas

    atlas = uv_atlas(anny_body, 64)
    surf = surface_texels(atlas)
    assert 0.3 < float(surf.float().mean()) < 0.9
    assert seen_share(surf, body=anny_body) == 1.0 and seen_share(~surf, atlas) == 0.0


def test_silhouette_iou():
    a = torch.zeros(3, 4, 4, dtype=torch.bool)
    b = a.clone()
    a[0, :2], b[0, :1] = True, True  # IoU 1/2
    a[1], b[1] = True, True  # IoU 1; frame 2 empty in both: skipped
    assert silhouette_iou(a, b) == pytest.approx(0.75)
    assert silhouette_iou(a.float(), b.numpy()) == pytest.approx(0.75)
    assert silhouette_iou(a[0], b[0]) == pytest.approx(0.5)
    with pytest.raises(ShapeError, match="b"):
        silhouette_iou(a, b[:2])
    with pytest.raises(InputError, match="empty"):
        silhouette_iou(a[2], b[2])


def test_person_psnr_and_ssim():
    g = torch.Generator().manual_seed(0)
    ref = torch.rand(2, 16, 16, 3, generator=g)
    mask = torch.zeros(2, 16, 16, dtype=torch.bool)
    mask[:, 4:12, 4:12] = True
    img = ref.clone()
    img[mask] += 0.1 * torch.tensor([1.0, -1.0, 1.0])
    assert person_psnr(img, ref, mask) == pytest.approx(20.0)
    assert person_psnr(ref, ref, mask) == math.inf and person_ssim(ref, ref, mask) == pytest.approx(1.0)
    img2 = ref.clone()
    img2[~mask] = 0  # outside the person it does not count for the PSNR
    assert person_psnr(img2, ref, mask) == math.inf
    assert 0 < person_ssim(ref + 0.2 * torch.rand(2, 16, 16, 3, generator=g), ref, mask) < 0.99
    assert person_ssim(img[0], ref[0], mask[0]) < 1.0
    with pytest.raises(ShapeError, match="mask"):
        person_psnr(img, ref, mask[0])
    with pytest.raises(InputError, match="empty"):
        person_ssim(img, ref, torch.zeros(2, 16, 16))
