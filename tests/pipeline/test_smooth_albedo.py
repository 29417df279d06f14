"""Smooth garment boundaries of the default albedo: a rendered close-up's boundary bands against a smooth reference."""

import numpy as np
import pytest
import torch

from relightnet.body import default_albedo
from relightnet.body.albedo import REGIONS, region_labels
from relightnet.light import ambient_light
from relightnet.pipeline.scene import avatar_albedo
from relightnet.pipeline.smooth_albedo import boundary_jaggedness, smooth_default_albedo
from relightnet.raster import look_at, perspective_camera
from relightnet.render.frame import TexturedAlbedo, render_mesh

TOP, SKIN, BOTTOM = REGIONS.index("top"), REGIONS.index("skin"), REGIONS.index("bottom")


def _region_map(body, albedo) -> np.ndarray:
    """(H, W) region of every pixel of an upper-body close-up (nearest region colour; −1 background)."""
    out = body({"pose": body.pose("apose")})
    cam = perspective_camera(look_at(torch.tensor([0.0, 1.25, 1.2]), torch.tensor([0.0, 1.25, 0.0])), (512, 512),
                             fov_deg=35)
    T = torch.zeros(body.num_verts, 9)
    T[:, 0] = 1.0
    r = render_mesh(out.verts[0], out.faces, T, albedo, ambient_light(1.0), cam, maps=True)
    regions = region_labels(body)
    vcol = default_albedo(body, texture_size=None, regions=regions).vertex
    table = torch.stack([vcol[int((regions == k).nonzero()[0, 0])] for k in range(len(REGIONS))])
    lab = (r.albedo[0][..., None, :] - table).abs().sum(-1).argmin(-1).numpy()
    lab[r.alpha[0].numpy() == 0] = -1
    return lab


@pytest.fixture(scope="module")
def maps(anny_body):
    old = default_albedo(anny_body)
    return (_region_map(anny_body, TexturedAlbedo(old.texture, anny_body.uv, anny_body.uv_faces)),
            _region_map(anny_body, smooth_default_albedo(anny_body)))


def test_boundary_jaggedness_tells_a_zigzag_from_a_smooth_curve():
    y, x = np.mgrid[0:200, 0:200]
    smooth = np.where(y > 100 + 20 * np.sin(x / 30.0), 1, 0)
    zigzag = np.where(y > 100 + 20 * np.sin(x / 30.0) + 4 * np.sign(np.sin(x * np.pi / 6)), 1, 0)
    assert boundary_jaggedness(smooth, 1, 0, sigma=10) < 0.5
    assert boundary_jaggedness(zigzag, 1, 0, sigma=10) > 1.5
    assert np.isnan(boundary_jaggedness(np.zeros((20, 20), int), 1, 0))


def test_default_albedo_garment_edges_are_smooth(maps):
    """Target: the neckline, sleeves and waist of the default albedo are not stair-stepped.

    Bounds: a smooth boundary drawn on 512² pixels strays from its 10-pixel smoothing by well under a pixel
    (quantisation and the true curvature of neckline and sleeves); the face-wise labels' zig-zag strays by
    more than a pixel along the neckline and sleeves."""
    old, new = maps
    j_old = boundary_jaggedness(old, TOP, SKIN, sigma=10)
    j_new = boundary_jaggedness(new, TOP, SKIN, sigma=10)
    assert j_old > 1.0 and j_new < 0.85 and j_new < 0.6 * j_old, (j_old, j_new)
    waist_old, waist_new = (boundary_jaggedness(m, TOP, BOTTOM, sigma=10) for m in maps)
    assert waist_new < 0.85 and waist_new < waist_old, (waist_old, waist_new)


def test_smooth_albedo_keeps_the_regions_where_they_were(maps):
    old, new = maps
    body = old >= 0
    assert (old[body] == new[body]).mean() > 0.97
    for k, tol in ((TOP, 0.05), (SKIN, 0.05), (BOTTOM, 0.1)):  # the bottom is a thin strip in this close-up
        assert abs((new == k).sum() - (old == k).sum()) < tol * (old == k).sum()


def test_avatar_default_albedo_is_the_smooth_one(anny_body):
    a = avatar_albedo(anny_body)
    assert isinstance(a, TexturedAlbedo) and a.tex.shape == (1024, 1024, 3)
    assert float(a.tex.min()) >= 0.02 - 1e-6 and float(a.tex.max()) <= 0.9 + 1e-6  # float32 of the clamp
