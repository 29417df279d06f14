import math

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.raster import Camera, default_camera, look_at, orthographic_camera, perspective_camera
from relightnet.raster.camera import fov_projection, ndc_to_pixel, perspective_projection, pixel_to_ndc


def test_look_at_is_a_rigid_transform_facing_the_target():
    eye = torch.tensor([[1.0, 2.0, 3.0], [-2.0, 0.5, -1.0]])
    target = torch.tensor([[0.0, 1.0, 0.0], [0.5, 0.0, 0.3]])
    view = look_at(eye, target)
    cam = Camera(view, fov_projection(40.0, (30, 40)).expand(2, 4, 4), (30, 40))
    R = cam.R
    assert torch.allclose(R @ R.transpose(1, 2), torch.eye(3).expand(2, 3, 3), atol=1e-6)
    assert torch.allclose(torch.linalg.det(R), torch.ones(2), atol=1e-6)
    assert torch.allclose(cam.position, eye, atol=1e-5)
    # the target lies straight ahead (−z) and projects to the image centre
    tv = cam.world_to_view(target[:, None])[:, 0]
    assert torch.allclose(tv[:, :2], torch.zeros(2, 2), atol=1e-5)
    assert (tv[:, 2] < 0).all()
    assert torch.allclose(cam.project(target[:, None])[:, 0], torch.tensor([[20.0, 15.0]] * 2), atol=1e-4)
    # world up stays up in the image
    up = cam.project((target + torch.tensor([0.0, 0.1, 0.0]))[:, None])[:, 0]
    assert (up[:, 1] < 15.0).all()


def test_intrinsics_projection_formula():
    fx, fy, cx, cy = 50.0, 60.0, 17.0, 11.0
    size = (24, 32)
    cam = perspective_camera(torch.eye(4)[None], size, intrinsics=(fx, fy, cx, cy))
    p = torch.tensor([[0.3, -0.2, -2.0], [-0.1, 0.4, -1.5]])
    uv = cam.project(p)[0]
    expect = torch.stack([fx * p[:, 0] / -p[:, 2] + cx, -fy * p[:, 1] / -p[:, 2] + cy], dim=1)
    assert torch.allclose(uv, expect, atol=1e-4)
    clip = cam.transform(p)[0]
    assert torch.allclose(clip[:, 3], -p[:, 2])
    # near plane maps to NDC z = -1, far plane to +1
    P = perspective_projection(fx, fy, cx, cy, size, near=0.5, far=20.0)[0]
    for z, ndc in ((-0.5, -1.0), (-20.0, 1.0)):
        c = P @ torch.tensor([0.0, 0.0, z, 1.0])
        assert math.isclose(c[2] / c[3], ndc, abs_tol=1e-5)


def test_fov_matches_intrinsics_and_pixel_convention():
    size = (40, 60)
    P = fov_projection(90.0, size)[0]
    # 90° vertical FOV: fy = H/2; the top edge of the image is at y/(-z) = 1
    cam = Camera(torch.eye(4)[None], P[None], size)
    uv = cam.project(torch.tensor([[0.0, 1.0, -1.0], [1.0, 0.0, -1.0]]))[0]
    assert torch.allclose(uv, torch.tensor([[30.0, 0.0], [50.0, 20.0]]), atol=1e-4)
    xy = torch.tensor([[-1.0, 1.0], [1.0, -1.0], [0.0, 0.0]])
    assert torch.allclose(ndc_to_pixel(xy, size), torch.tensor([[0.0, 0.0], [60.0, 40.0], [30.0, 20.0]]))
    assert torch.allclose(pixel_to_ndc(ndc_to_pixel(xy, size), size), xy)


def test_orthographic_and_depth_to_view():
    size = (20, 30)
    view = look_at([0.0, 0.0, 5.0], [0.0, 0.0, 0.0])
    cam = orthographic_camera(view, size, height=2.0, near=1.0, far=9.0)
    clip = cam.transform(torch.tensor([[1.5, 1.0, 0.0], [0.0, 0.0, 2.0]]))[0]
    assert torch.allclose(clip[:, 3], torch.ones(2))
    assert torch.allclose(clip[0, :2], torch.tensor([1.0, 1.0]))
    ndc_z = clip[:, 2]
    assert torch.allclose(cam.depth_to_view(ndc_z[None]), torch.tensor([[5.0, 3.0]]), atol=1e-5)
    pcam = default_camera(size=size)
    pts = torch.tensor([[0.0, 0.85, 0.0], [0.2, 1.0, -1.0]])
    c = pcam.transform(pts)[0]
    assert torch.allclose(pcam.depth_to_view((c[:, 2] / c[:, 3])[None])[0], torch.tensor([3.0, 4.0]), atol=1e-4)
    inf = torch.tensor([[math.inf]])
    assert torch.isinf(pcam.depth_to_view(inf)).all()


def test_default_camera_frames_a_standing_person():
    cam = default_camera(size=(512, 512))
    assert torch.allclose(cam.R[0], torch.eye(3))
    assert torch.allclose(cam.position[0], torch.tensor([0.0, 0.85, 3.0]))
    feet_head = torch.tensor([[0.0, 0.0, 0.1], [0.0, 1.7, 0.0], [0.3, 0.9, 0.2], [-0.3, 0.9, 0.2]])
    uv = cam.project(feet_head)[0]
    assert ((uv > 0) & (uv < 512)).all()
    assert uv[0, 1] > 470 and uv[1, 1] < 40  # the body fills most of the height
    batch = default_camera(size=(64, 48), batch_size=3)
    assert batch.view.shape == (3, 4, 4) and batch.size == (64, 48)
    assert batch.transform(torch.zeros(5, 3)).shape == (3, 5, 4)


def test_batched_vertices_and_errors():
    cam = perspective_camera(look_at(torch.tensor([[0.0, 0, 2], [0, 0, 3]]), torch.zeros(3)), (8, 8), fov_deg=50.0)
    v = torch.rand(2, 4, 3)
    assert torch.allclose(cam.transform(v)[1], cam.transform(v[1])[1])
    with pytest.raises(ShapeError):
        cam.transform(torch.rand(3, 4, 3))
    with pytest.raises(InputError):
        look_at([0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(InputError):
        look_at([0.0, 1.0, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(InputError):
        fov_projection(0.0, (8, 8))
    with pytest.raises(InputError):
        perspective_camera(torch.eye(4)[None], (8, 8))
    with pytest.raises(ShapeError):
        Camera(torch.eye(4)[None], torch.eye(4)[None].expand(2, 4, 4), (8, 8))
