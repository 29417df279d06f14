import math

import numpy as np
import pytest
import torch
from skimage.metrics import structural_similarity

from relightnet.checks import InputError, ShapeError
from relightnet.pipeline.metrics import gaussian_window, masked_rmse, psnr, ssim, ssim_map, temporal_error


def _pair(b=2, h=40, w=36, seed=0):
    g = torch.Generator().manual_seed(seed)
    x = torch.rand(b, 3, h, w, generator=g)
    mask = torch.zeros(b, h, w)
    mask[:, 8:32, 10:28] = 1
    return x, mask


def test_identical_images_are_perfect():
    x, m = _pair()
    assert torch.equal(masked_rmse(x, x.clone(), m), torch.zeros(2, dtype=torch.float64))
    p = psnr(x, x.clone(), m)
    assert p.shape == (2,) and torch.isinf(p).all() and (p > 0).all()
    assert torch.equal(ssim(x, x.clone(), m), torch.ones(2, dtype=torch.float64))
    assert torch.equal(ssim_map(x, x.clone()), torch.ones_like(x, dtype=torch.float64))


def test_constant_offset_inside_the_mask():
    x, m = _pair()
    x = x * 0.8
    for c in (0.01, 0.05, 0.2):
        y = x + c
        assert torch.allclose(masked_rmse(y, x, m), torch.full((2,), c, dtype=torch.float64), atol=1e-7)
        assert torch.allclose(psnr(y, x, m), torch.full((2,), -20 * math.log10(c), dtype=torch.float64), atol=1e-4)
        # data_range scales the peak: R = 2 adds 20 log10 2 dB.
        assert torch.allclose(psnr(y, x, m, data_range=2.0) - psnr(y, x, m),
                              torch.full((2,), 20 * math.log10(2), dtype=torch.float64), atol=1e-9)
    # A different offset per image gives a per-image RMSE.
    y = x + torch.tensor([0.1, 0.3])[:, None, None, None]
    assert torch.allclose(masked_rmse(y, x, m), torch.tensor([0.1, 0.3], dtype=torch.float64), atol=1e-7)


def test_rmse_known_value_and_masks_are_respected():
    x, m = _pair(b=1)
    y = x.clone()
    y[0, 0, 10, 12] += 0.6  # one channel of one masked pixel
    n = int(m.sum()) * 3
    assert masked_rmse(y, x, m).item() == pytest.approx(math.sqrt(0.36 / n), rel=1e-6)
    # Anything outside the mask is ignored by RMSE and PSNR ...
    z = y.clone()
    z[..., :8, :] = 5.0
    z[..., :, 30:] = -3.0
    assert masked_rmse(z, x, m).item() == pytest.approx(masked_rmse(y, x, m).item(), rel=1e-12)
    assert psnr(z, x, m).item() == pytest.approx(psnr(y, x, m).item(), rel=1e-12)
    # ... and by SSIM when it is farther from the mask than the window's radius (5 px).
    far = torch.ones_like(m, dtype=torch.bool)
    far[:, 3:37, 5:33] = False
    z = torch.where(far[:, None], torch.rand_like(y), y)
    assert ssim(z, x, m).item() == pytest.approx(ssim(y, x, m).item(), abs=1e-12)
    # Masks as (B, 1, H, W), bool or float, mean the same.
    assert masked_rmse(y, x, m[:, None] > 0.5).item() == masked_rmse(y, x, m).item()


def test_ssim_matches_skimage_in_the_interior():
    g = torch.Generator().manual_seed(3)
    x = torch.rand(1, 3, 48, 40, generator=g, dtype=torch.float64)
    y = (x + 0.15 * torch.randn(1, 3, 48, 40, generator=g, dtype=torch.float64)).clamp(0, 1)
    ours = ssim_map(x, y)[0].permute(1, 2, 0).numpy()
    _, ref = structural_similarity(x[0].permute(1, 2, 0).numpy(), y[0].permute(1, 2, 0).numpy(), channel_axis=2,
                                   data_range=1.0, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                                   full=True)
    # skimage's filter pads differently at the border; inside the 5-pixel margin both are the same formula.
    np.testing.assert_allclose(ours[5:-5, 5:-5], ref[5:-5, 5:-5], atol=1e-10)
    # Symmetric, at most 1, and it falls with the noise level.
    m = torch.ones(1, 48, 40)
    assert ssim(x, y, m).item() == pytest.approx(ssim(y, x, m).item(), abs=1e-12)
    worse = (x + 0.4 * torch.randn(1, 3, 48, 40, generator=g, dtype=torch.float64)).clamp(0, 1)
    assert ssim(x, worse, m).item() < ssim(x, y, m).item() < 1


def test_gaussian_window():
    w = gaussian_window()
    assert w.shape == (11,) and w.dtype == torch.float64
    assert w.sum().item() == pytest.approx(1.0, abs=1e-15)
    assert torch.equal(w, w.flip(0)) and w.argmax().item() == 5
    assert (w[6] / w[5]).item() == pytest.approx(math.exp(-1 / (2 * 1.5**2)), rel=1e-12)
    with pytest.raises(InputError, match="odd"):
        gaussian_window(10)


def test_temporal_error_known_cases():
    g = torch.Generator().manual_seed(1)
    gt = torch.rand(5, 3, 20, 24, generator=g)
    m = torch.zeros(5, 20, 24)
    m[:, 4:16, 6:18] = 1
    # A static offset (or any fixed error pattern) has no temporal error.
    pattern = 0.1 * torch.rand(1, 3, 20, 24, generator=g)
    assert temporal_error(gt + pattern, gt, m).item() == pytest.approx(0.0, abs=1e-7)
    assert temporal_error(gt.clone(), gt, m).item() == 0.0
    # A drift of c per frame gives exactly c; per pair too.
    c = 0.03
    drift = gt + c * torch.arange(5.0)[:, None, None, None]
    assert temporal_error(drift, gt, m).item() == pytest.approx(c, rel=1e-5)
    per = temporal_error(drift, gt, m, reduction="none")
    assert per.shape == (4,) and torch.allclose(per, torch.full((4,), c, dtype=torch.float64), rtol=1e-5)
    # Only pixels masked in both frames of a pair count.
    m2 = torch.zeros(3, 20, 24)
    m2[0, :, :12] = 1
    m2[1, :, 6:18] = 1
    m2[2, :, 12:] = 1
    x = gt[:3].clone()
    x[1, :, :, :6] += 1.0  # masked in frame 1 only: never in both
    x[1, :, :, 18:] += 1.0
    assert temporal_error(x, gt[:3], m2).item() == 0.0
    x[1, :, :, 6:12] += 0.5  # masked in frames 0 and 1: pair 0; pair 1 sees frames 1, 2 only in 12:18
    per = temporal_error(x, gt[:3], m2, reduction="none")
    assert per[0].item() == pytest.approx(0.5, rel=1e-6) and per[1].item() == 0.0
    assert temporal_error(x, gt[:3], m2).item() == pytest.approx(0.5 * 6 / 12, rel=1e-6)
    # A pair whose masks do not overlap is NaN per pair and left out of the pooled mean.
    m3 = m2.clone()
    m3[1] = 0
    m3[1, :, :3] = 1
    m3[2] = 0
    m3[2, :, 20:] = 1
    per = temporal_error(x, gt[:3], m3, reduction="none")
    assert torch.isnan(per[1]) and torch.isfinite(per[0])


def test_bad_inputs():
    x, m = _pair()
    with pytest.raises(InputError, match="empty"):
        masked_rmse(x, x, torch.zeros_like(m))
    with pytest.raises(ShapeError):
        masked_rmse(x, x[:, :, :-1], m)
    with pytest.raises(ShapeError):
        psnr(x, x, m[:1])
    with pytest.raises(InputError, match="2 frames"):
        temporal_error(x[:1], x[:1], m[:1])
    with pytest.raises(InputError, match="reduction"):
        temporal_error(x, x, m, reduction="sum")
    with pytest.raises(InputError, match="two consecutive"):
        mm = torch.zeros_like(m)
        mm[0, 0, 0] = 1
        temporal_error(x, x, mm)
    with pytest.raises(ShapeError, match="SSIM"):
        ssim(x[..., :4, :4], x[..., :4, :4], m[..., :4, :4])
    with pytest.raises(InputError, match="torch.Tensor"):
        masked_rmse(x.numpy(), x, m)
