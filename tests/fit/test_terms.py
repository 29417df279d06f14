"""The silhouette term works at a small resolution and still measures image pixels."""

import numpy as np
import torch
from scipy import ndimage

from relightnet.fit.masks import SILHOUETTE_HEIGHT
from relightnet.fit.terms import outline_matches, silhouette_targets, silhouette_term


def _person(size=(720, 1280), box=(100, 600, 500, 700)) -> torch.Tensor:
    """(1, H, W) a rectangle 'person' rows y0:y1, columns x0:x1."""
    y0, y1, x0, x1 = box
    m = torch.zeros(1, *size)
    m[0, y0:y1, x0:x1] = 1
    return m


def test_targets_are_at_the_working_resolution_in_image_units():
    m = _person()
    t = silhouette_targets(m)
    fx, fy = t.factor
    assert abs(fy * 500 - SILHOUETTE_HEIGHT) <= 1 and abs(fx - fy) < 2e-3  # the person ~160 px tall
    assert t.outside.shape[-2:] == (round(720 * fy), round(1280 * fx)) and bool(t.valid.all())
    # the working distance transform, in image pixels, is the full-resolution one to within the
    # resampling: the outline moves by at most one working pixel (1/f image pixels), and the
    # lookup is bilinear between working pixel centres (another 1/f)
    full = ndimage.distance_transform_edt(m[0].numpy() < 0.5)
    ys, xs = np.mgrid[20:700:37, 30:1250:41]
    px = torch.tensor(np.stack([xs.ravel() + 0.5, ys.ravel() + 0.5], 1), dtype=torch.float32)
    grid = torch.stack([px[:, 0] * fx * 2 / t.outside.shape[-1] - 1, px[:, 1] * fy * 2 / t.outside.shape[-2] - 1],
                       -1)[None, :, None]
    work = torch.nn.functional.grid_sample(t.outside, grid, align_corners=False, padding_mode="border")
    err = (work.flatten() / fy - torch.from_numpy(full[ys.ravel(), xs.ravel()]).float()).abs()
    assert float(err.max()) <= 2.0 / fy, float(err.max())


def test_masks_below_the_image_resolution_give_the_same_targets():
    m = _person()
    low = torch.nn.functional.interpolate(m[:, None], size=(180, 320), mode="area")[:, 0]
    a, b = silhouette_targets(m), silhouette_targets(low, size=(720, 1280))
    assert b.factor[1] <= 180 / 720  # never finer than the masks
    pts = torch.tensor([[[640.0, 350.0], [400.0, 50.0], [900.0, 710.0]]])
    scale = torch.tensor([550.0])
    ea, eb = silhouette_term(pts, a, scale), silhouette_term(pts, b, scale)
    # points 100-250 px outside the person: the terms agree to a few working pixels of outline
    torch.testing.assert_close(eb, ea, rtol=0.1, atol=0)


def test_silhouette_term_is_zero_on_the_outline_and_grows_outside():
    m = _person()
    t = silhouette_targets(m, n_outline=64)
    fx, fy = t.factor
    on = t.outline / torch.tensor([fx, fy])  # outline points in image pixels: inside, and matched exactly
    scale = torch.tensor([550.0])
    assert float(silhouette_term(on, t, scale)) < 1e-10
    shifted = [float(silhouette_term(on + torch.tensor([dx, 0.0]), t, scale)) for dx in (20.0, 60.0, 180.0)]
    assert shifted[0] > 0 and shifted[0] < shifted[1] < shifted[2]


def test_outline_matches_are_the_nearest_vertices():
    g = torch.Generator().manual_seed(0)
    t = silhouette_targets(_person(), n_outline=32)
    px = torch.rand(2, 50, 2, generator=g) * torch.tensor([1280.0, 720.0])
    t2 = silhouette_targets(torch.cat([_person(), _person(box=(50, 650, 300, 500))]), n_outline=32)
    for tt, p in ((t, px[:1]), (t2, px)):
        work = p * torch.tensor(tt.factor)
        d = torch.cdist(tt.outline.double(), work.double())
        got = outline_matches(p, tt)
        # the nearest vertex, or one tied with it to float32 rounding
        chosen = d.gather(2, got[..., None])[..., 0]
        assert bool((chosen - d.amin(-1) <= 1e-3).all())
