"""Blender cameras equal to relightnet's: Blender's own projection against Camera.project."""

import math

import pytest
import torch

from relightnet.blender.camera import blender_camera
from relightnet.checks import InputError, ShapeError
from relightnet.raster import default_camera, look_at, orthographic_camera, perspective_camera


def _cameras():
    eye, target = torch.tensor([1.2, 1.6, 2.5]), torch.tensor([0.1, 0.9, -0.2])
    return {
        "default 64x48": default_camera((48, 64)),
        "off-centre principal point, portrait": perspective_camera(
            look_at(eye, target), (80, 50), intrinsics=(70.0, 70.0, 21.0, 47.5), near=0.2, far=30.0),
        "orthographic": orthographic_camera(look_at(eye, target), (40, 60), height=2.2, near=0.5, far=9.0),
    }


def test_settings_of_the_default_camera():
    bc = blender_camera(default_camera(64))
    f_px = 32 / math.tan(math.radians(17.5))
    assert bc.type == "PERSP" and bc.resolution == (64, 64)
    assert bc.lens == pytest.approx(f_px / 64 * 36.0, rel=1e-6)
    assert bc.shift_x == pytest.approx(0.0, abs=1e-9) and bc.shift_y == pytest.approx(0.0, abs=1e-9)
    assert bc.clip_start == pytest.approx(0.1, rel=1e-4) and bc.clip_end == pytest.approx(100.0, rel=1e-3)
    m = torch.tensor(bc.matrix_world)
    assert torch.allclose(m[:3, 3], torch.tensor([0.0, -3.0, 0.85], dtype=m.dtype), atol=1e-6)  # eye, z up
    assert torch.allclose(-m[:3, 2], torch.tensor([0.0, 1.0, 0.0], dtype=m.dtype), atol=1e-6)  # looks along +y_b


def test_blender_projects_points_where_we_do():
    from relightnet.blender._bpy import reset
    from relightnet.blender.scene import _camera

    reset()
    from bpy_extras.object_utils import world_to_camera_view  # importable once bpy is
    from mathutils import Vector

    from relightnet.blender import world_to_blender

    pts = torch.tensor([[0.0, 0.85, 0.0], [0.4, 1.5, 0.3], [-0.5, 0.2, -0.4], [0.3, 0.7, 0.5]])
    for name, cam in _cameras().items():
        bpy = reset()
        scene = bpy.context.scene
        ob, bc = _camera(bpy, cam)
        scene.camera = ob
        scene.render.resolution_x, scene.render.resolution_y = bc.resolution
        scene.render.resolution_percentage = 100
        bpy.context.view_layer.update()
        H, W = cam.size
        ours = cam.project(pts)[0]
        pb = world_to_blender(pts.double())
        for p, uv in zip(pb.tolist(), ours.tolist(), strict=True):
            x, y, depth = world_to_camera_view(scene, ob, Vector(p))  # (0, 0) = bottom-left of the frame
            assert x * W == pytest.approx(uv[0], abs=1e-3), name
            assert (1 - y) * H == pytest.approx(uv[1], abs=1e-3), name
            assert depth > 0
        assert ob.data.clip_start == pytest.approx(bc.clip_start) and ob.data.type == bc.type


def test_cameras_blender_cannot_represent():
    cam = perspective_camera(look_at(torch.tensor([0.0, 1.0, 3.0]), torch.tensor([0.0, 1.0, 0.0])), (32, 32),
                             intrinsics=(40.0, 50.0, 16.0, 16.0))
    with pytest.raises(InputError, match="square pixels"):
        blender_camera(cam)
    with pytest.raises(ShapeError, match="one camera"):
        blender_camera(default_camera(16, batch_size=2))
