import math
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
import trimesh
from scipy import ndimage

from relightnet.checks import InputError, ShapeError
from relightnet.raster import (
    Fragments,
    look_at,
    orthographic_camera,
    perspective_camera,
    rasterize,
)

sys.path.insert(0, str(Path(__file__).parent))
from reference import reference_rasterize  # noqa: E402

H, W = 24, 32


def _ortho(size=(H, W), height=2.0):
    """Orthographic camera at +z looking at the origin: NDC x = x / (height/2 · W/H)."""
    view = look_at(torch.tensor([0.0, 0.0, 5.0]), torch.tensor([0.0, 0.0, 0.0]))
    return orthographic_camera(view, size, height=height, near=0.1, far=10.0)


def _pix_verts(uv, size=(H, W), z=0.0):
    """World vertices (orthographic camera of _ortho) landing on continuous pixel coords uv."""
    h, w = size
    uv = torch.as_tensor(uv, dtype=torch.float64)
    x = (uv[:, 0] / w * 2 - 1) * (w / h)
    y = 1 - uv[:, 1] / h * 2
    return torch.stack([x, y, torch.full_like(x, z)], dim=1)


@pytest.mark.parametrize("seed", range(5))
def test_matches_reference_on_random_meshes(seed):
    g = torch.Generator().manual_seed(seed)
    V, F = 30, 16
    verts = (torch.rand(2, V, 3, generator=g, dtype=torch.float64) - 0.5) * torch.tensor([4.0, 3.0, 6.0],
                                                                                           dtype=torch.float64)
    faces = torch.randint(0, V, (F, 3), generator=g)
    view = look_at(torch.tensor([[0.0, 0, 2.0], [0.3, 0.2, 1.5]], dtype=torch.float64),
                   torch.tensor([0.0, 0, 0], dtype=torch.float64), dtype=torch.float64)
    cam = perspective_camera(view, (H, W), fov_deg=60.0)
    vc = cam.transform(verts)
    assert (vc[..., 3] <= 0).any(), "the test wants vertices behind the camera"
    frags = rasterize(vc, faces, (H, W))
    fid, bary, depth = reference_rasterize(vc, faces, (H, W))
    assert torch.equal(frags.face_id, fid)
    cov = fid >= 0
    assert cov.sum() > 100
    assert torch.allclose(frags.bary[cov], bary[cov], atol=1e-5, rtol=0)
    assert torch.allclose(frags.depth[cov], depth[cov], atol=1e-7, rtol=0)
    assert torch.isinf(frags.depth[~cov]).all()
    assert (frags.bary[~cov] == 0).all()


def test_matches_reference_float32_and_culling():
    g = torch.Generator().manual_seed(11)
    verts = (torch.rand(40, 3, generator=g) - 0.5) * 3
    faces = torch.randint(0, 40, (20, 3), generator=g)
    cam = perspective_camera(look_at([0.0, 0.0, 3.0], [0.0, 0.0, 0.0]), (H, W), fov_deg=50.0)
    vc = cam.transform(verts)
    for cull in (False, True):
        frags = rasterize(vc, faces, (H, W), cull_backfaces=cull)
        fid, bary, _ = reference_rasterize(vc, faces, (H, W), cull_backfaces=cull)
        assert torch.equal(frags.face_id, fid)
        cov = fid >= 0
        assert frags.bary.dtype == torch.float32
        assert torch.allclose(frags.bary[cov].double(), bary[cov], atol=1e-5)


def _coverage_count(verts_clip, faces, size, cull=False):
    """Number of triangles covering each pixel: batch element f holds only triangle f."""
    F = faces.shape[0]
    tri = verts_clip[0][faces].reshape(3 * F, 4)  # unshared vertices
    behind = torch.tensor([0.0, 0.0, -2.0, -1.0], dtype=tri.dtype)
    own = torch.arange(F)[:, None] == torch.arange(3 * F)[None, :] // 3
    vc = torch.where(own[..., None], tri[None], behind)
    frags = rasterize(vc, torch.arange(3 * F).view(F, 3), size, cull_backfaces=cull)
    assert torch.equal(frags.pix_face, torch.div(frags.pix, size[0] * size[1], rounding_mode="floor"))
    return frags.mask.long().sum(0, keepdim=True)


def test_icosphere_is_watertight():
    mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
    verts = torch.tensor(mesh.vertices, dtype=torch.float32)
    faces = torch.tensor(mesh.faces, dtype=torch.long)
    size = (48, 64)
    cam = perspective_camera(look_at([0.3, 0.2, 3.0], [0.0, 0.0, 0.0]), size, fov_deg=45.0)
    vc = cam.transform(verts)
    frags = rasterize(vc, faces, size)
    mask = frags.mask[0].numpy()
    assert mask.sum() > 500
    assert (ndimage.binary_fill_holes(mask) == mask).all()
    # front faces cover every silhouette pixel exactly once, back faces likewise
    front = _coverage_count(vc, faces, size, cull=True)[0]
    both = _coverage_count(vc, faces, size)[0]
    assert set(front[frags.mask[0]].unique().tolist()) == {1}
    assert set(both[frags.mask[0]].unique().tolist()) == {2}
    assert (both[~frags.mask[0]] == 0).all()
    # with culling, the visible faces are the front faces
    culled = rasterize(vc, faces, size, cull_backfaces=True)
    assert torch.equal(culled.face_id, frags.face_id)


def test_shared_edges_through_pixel_centres_cover_once():
    cam = _ortho()
    # an 8×8 quad with corners on pixel centres; the diagonal passes through pixel centres
    corners = [(4.5, 3.5), (12.5, 3.5), (12.5, 11.5), (4.5, 11.5)]
    verts = _pix_verts(corners).float()
    vc = cam.transform(verts)
    faces = torch.tensor([[0, 1, 2], [0, 2, 3]])
    count = _coverage_count(vc, faces, (H, W))[0]
    assert count.max() == 1
    # top-left rule: left and top edges in, right and bottom edges out → exactly 8×8 pixels
    assert count.sum() == 64
    assert count[3:11, 4:12].sum() == 64
    # a fan of 6 triangles around a vertex sitting on a pixel centre, rim on pixel centres too
    rim = [(20.5, 12.5), (16.5, 4.5), (10.5, 6.5), (8.5, 14.5), (14.5, 20.5), (22.5, 18.5)]
    verts = _pix_verts([(15.5, 12.5)] + rim).float()
    faces = torch.tensor([[0, 1 + i, 1 + (i + 1) % 6] for i in range(6)])
    count = _coverage_count(cam.transform(verts), faces, (H, W))[0]
    assert count.max() == 1
    whole = rasterize(cam.transform(verts), faces, (H, W)).mask[0]
    assert torch.equal(whole, count == 1)


def test_depth_order_independent_of_face_order():
    cam = perspective_camera(look_at([0.0, 0.0, 3.0], [0.0, 0.0, 0.0]), (H, W), fov_deg=60.0)
    near = torch.tensor([[-1.0, -1.0, 0.5], [1.0, -1.0, 0.5], [0.0, 1.0, 0.5]])
    far = torch.tensor([[-1.5, -1.0, -0.5], [1.5, -1.0, -0.5], [0.0, 1.5, -0.5]])
    verts = torch.cat([near, far])
    vc = cam.transform(verts)
    for faces, near_id in ((torch.tensor([[0, 1, 2], [3, 4, 5]]), 0), (torch.tensor([[3, 4, 5], [0, 1, 2]]), 1)):
        frags = rasterize(vc, faces, (H, W))
        only_near = rasterize(vc, faces[near_id:near_id + 1], (H, W)).mask
        assert (frags.face_id[only_near] == near_id).all()
        assert (frags.face_id[frags.mask & ~only_near] == 1 - near_id).all()
        assert (frags.mask & ~only_near).any()


def test_half_screen_plane_exact_pixel_count():
    cam = _ortho()
    # left half of the screen: x from -big to the vertical line through the image centre
    verts = _pix_verts([(-40.0, -40.0), (16.0, -40.0), (16.0, 70.0), (-40.0, 70.0)]).float()
    frags = rasterize(cam.transform(verts), torch.tensor([[0, 1, 2], [0, 2, 3]]), (H, W))
    assert frags.mask.sum() == H * W // 2
    assert frags.mask[0, :, :16].all()
    # a perspective camera facing a wall that fills exactly the lower half
    size = (32, 32)
    cam = perspective_camera(look_at([0.0, 0.0, 2.0], [0.0, 0.0, 0.0]), size, fov_deg=90.0)
    wall = torch.tensor([[-5.0, -5.0, 0.0], [5.0, -5.0, 0.0], [5.0, 0.0, 0.0], [-5.0, 0.0, 0.0]])
    frags = rasterize(cam.transform(wall), torch.tensor([[0, 1, 2], [0, 2, 3]]), size)
    assert frags.mask.sum() == 32 * 16
    assert frags.mask[0, 16:].all()
    view_depth = cam.depth_to_view(frags.depth)
    assert torch.allclose(view_depth[0, 16:, 15:17], torch.full((16, 2), 2.0), atol=0.05)


def test_ground_plane_behind_camera_does_not_wrap():
    size = (32, 40)
    cam = perspective_camera(look_at([0.0, 1.6, 0.0], [0.0, 1.6, -1.0]), size, fov_deg=60.0, far=1000.0)
    ground = torch.tensor([[-100.0, 0.0, -100.0], [100.0, 0.0, -100.0], [100.0, 0.0, 100.0], [-100.0, 0.0, 100.0]])
    faces = torch.tensor([[0, 2, 1], [0, 3, 2]])
    vc = cam.transform(ground)
    assert (vc[..., 3] < 0).any()
    frags = rasterize(vc, faces, size)
    assert frags.mask[0, 16:].all()
    assert not frags.mask[0, :16].any()
    fid, _, _ = reference_rasterize(vc, faces, size)
    assert torch.equal(frags.face_id, fid)
    # depth grows towards the horizon
    d = frags.depth[0, 16:, 20]
    assert (d[:-1] > d[1:]).all()


def test_batch_equals_separate_calls():
    g = torch.Generator().manual_seed(3)
    verts = torch.rand(2, 20, 3, generator=g) - 0.5
    faces = torch.randint(0, 20, (12, 3), generator=g)
    view = look_at(torch.tensor([[0.0, 0.0, 2.0], [1.0, 0.5, 2.0]]), torch.zeros(3))
    cam = perspective_camera(view, (H, W), fov_deg=50.0)
    vc = cam.transform(verts)
    both = rasterize(vc, faces, (H, W))
    for b in range(2):
        one = rasterize(vc[b:b + 1], faces, (H, W))
        assert torch.equal(both.face_id[b], one.face_id[0])
        assert torch.allclose(both.bary[b], one.bary[0])


def test_empty_and_offscreen():
    vc = torch.tensor([[[5.0, 5.0, 0.0, 1.0], [6.0, 5.0, 0.0, 1.0], [5.0, 6.0, 0.0, 1.0]]])
    frags = rasterize(vc, torch.tensor([[0, 1, 2]]), (H, W))
    assert not frags.mask.any() and frags.pix.numel() == 0
    frags = rasterize(vc, torch.zeros(0, 3, dtype=torch.long), (H, W))
    assert (frags.face_id == -1).all() and torch.isinf(frags.depth).all()
    behind = torch.tensor([[[0.0, 0.0, 0.5, -1.0], [1.0, 0.0, 0.5, -1.0], [0.0, 1.0, 0.5, -1.0]]])
    assert not rasterize(behind, torch.tensor([[0, 1, 2]]), (H, W)).mask.any()


def test_validation_errors():
    vc = torch.zeros(1, 3, 4)
    with pytest.raises(ShapeError):
        rasterize(torch.zeros(3, 4), torch.tensor([[0, 1, 2]]), (H, W))
    with pytest.raises(ShapeError):
        rasterize(vc, torch.tensor([0, 1, 2]), (H, W))
    with pytest.raises(InputError):
        rasterize(vc + torch.tensor([0.0, 0, 0, 1]), torch.tensor([[0, 1, 3]]), (H, W))
    with pytest.raises(InputError):
        rasterize(torch.full((1, 3, 4), math.nan), torch.tensor([[0, 1, 2]]), (H, W))


def test_fragments_dense_round_trip():
    cam = _ortho()
    verts = _pix_verts([(2.0, 2.0), (20.0, 3.0), (8.0, 20.0)]).float()
    frags = rasterize(cam.transform(verts), torch.tensor([[0, 1, 2]]), (H, W))
    again = Fragments.from_dense(frags.face_id, frags.bary, frags.depth)
    assert torch.equal(again.face_id, frags.face_id)
    assert torch.equal(again.bary, frags.bary)
    assert torch.equal(again.mask, frags.mask)
    assert torch.allclose(frags.bary.sum(-1)[frags.mask], torch.ones(int(frags.mask.sum())))
    assert frags.size == (H, W) and frags.batch_size == 1
    assert np.isclose(frags.mask.sum().item(), 0.5 * abs((20 - 2) * (20 - 2) - (8 - 2) * (3 - 2)), rtol=0.1)


@pytest.mark.slow
def test_compiled_kernels_match_eager():
    """compile=True (torch.compile, or its eager fallback) gives bit-identical fragments."""
    g = torch.Generator().manual_seed(7)
    verts = (torch.rand(2, 40, 3, generator=g) - 0.5) * torch.tensor([4.0, 3.0, 6.0])
    faces = torch.randint(0, 40, (24, 3), generator=g)
    view = look_at(torch.tensor([[0.0, 0, 2.0], [0.3, 0.2, 1.5]]), torch.tensor([0.0, 0, 0]))
    vc = perspective_camera(view, (H, W), fov_deg=60.0).transform(verts)
    eager = rasterize(vc, faces, (H, W))
    compiled = rasterize(vc, faces, (H, W), compile=True)
    assert torch.equal(compiled.face_id, eager.face_id)
    assert torch.equal(compiled.bary, eager.bary)
    assert torch.equal(compiled.depth, eager.depth)


def test_rasterize_and_interpolate_on_device_match_cpu(device, dtype):
    from relightnet.raster import interpolate

    g = torch.Generator().manual_seed(21)
    verts = (torch.rand(40, 3, generator=g, dtype=torch.float64) - 0.5) * 3
    faces = torch.randint(0, 40, (24, 3), generator=g)
    cam = perspective_camera(look_at(torch.tensor([0.0, 0.0, 3.0], dtype=torch.float64),
                                     torch.tensor([0.0, 0.0, 0.0], dtype=torch.float64), dtype=torch.float64),
                             (H, W), fov_deg=50.0)
    vc = cam.transform(verts).to(dtype)
    attr = torch.rand(40, 4, generator=g, dtype=torch.float64).to(dtype)
    ref = rasterize(vc, faces, (H, W))
    frags = rasterize(vc.to(device), faces.to(device), (H, W))
    assert frags.face_id.device.type == device.type and frags.bary.dtype == dtype
    assert torch.equal(frags.face_id.cpu(), ref.face_id) and (ref.face_id >= 0).sum() > 100
    tol = 1e-5 if dtype == torch.float32 else 1e-12
    torch.testing.assert_close(frags.bary.cpu(), ref.bary, atol=tol, rtol=0)
    out = interpolate(attr.to(device), frags, faces.to(device))
    torch.testing.assert_close(out.cpu(), interpolate(attr, ref, faces), atol=tol, rtol=0)


def test_interpolate_gradcheck(device):
    from relightnet.raster import interpolate

    g = torch.Generator().manual_seed(22)
    verts = (torch.rand(12, 3, generator=g, dtype=torch.float64) - 0.5) * 3
    faces = torch.randint(0, 12, (6, 3), generator=g).to(device)
    cam = perspective_camera(look_at(torch.tensor([0.0, 0.0, 3.0], dtype=torch.float64),
                                     torch.tensor([0.0, 0.0, 0.0], dtype=torch.float64), dtype=torch.float64),
                             (8, 8), fov_deg=50.0)
    frags = rasterize(cam.transform(verts).to(device), faces, (8, 8))
    assert (frags.face_id >= 0).any()
    attr = torch.rand(12, 2, generator=g, dtype=torch.float64).to(device).requires_grad_(True)
    assert torch.autograd.gradcheck(lambda a: interpolate(a, frags, faces), (attr,))
