import pytest
import torch

from relightnet.checks import ShapeError
from relightnet.sh import camera_normals_to_light, light_to_world, rotate_sh, sh_basis, world_to_light
from relightnet.sh.frames import WORLD_TO_LIGHT, rotation_world_to_light


def test_axes_as_design_md():
    # x_light = +z_world (toward camera), y_light = +x_world (image right), z_light = +y_world (up).
    assert world_to_light(torch.tensor([0.0, 0.0, 1.0])).tolist() == [1.0, 0.0, 0.0]
    assert world_to_light(torch.tensor([1.0, 0.0, 0.0])).tolist() == [0.0, 1.0, 0.0]
    assert world_to_light(torch.tensor([0.0, 1.0, 0.0])).tolist() == [0.0, 0.0, 1.0]
    assert torch.det(WORLD_TO_LIGHT) == 1


def test_round_trip_and_matrix_agree():
    v = torch.randn(7, 3)
    torch.testing.assert_close(light_to_world(world_to_light(v)), v)
    torch.testing.assert_close(world_to_light(v), v @ WORLD_TO_LIGHT.T)


def test_world_rotation_in_light_frame_commutes():
    R = torch.linalg.qr(torch.randn(3, 3, dtype=torch.float64))[0]
    R = R * torch.sign(torch.det(R))
    v = torch.randn(5, 3, dtype=torch.float64)
    torch.testing.assert_close(world_to_light(v @ R.T), world_to_light(v) @ rotation_world_to_light(R).T)


def test_camera_relative_normals_equivalent_to_rotating_light():
    # Shading a world normal with a camera-relative light == rotating the light to world.
    g = torch.Generator().manual_seed(1)
    R = torch.linalg.qr(torch.randn(3, 3, generator=g, dtype=torch.float64))[0]
    R = R * torch.sign(torch.det(R))
    sh = torch.randn(9, 3, generator=g, dtype=torch.float64)
    n = torch.nn.functional.normalize(torch.randn(6, 3, generator=g, dtype=torch.float64), dim=-1)
    a = sh_basis(camera_normals_to_light(n, R), 2) @ sh
    sh_world = rotate_sh(sh, rotation_world_to_light(R.T))
    b = sh_basis(world_to_light(n), 2) @ sh_world
    torch.testing.assert_close(a, b)
    # Default camera (identity rotation) is the plain world -> light map.
    torch.testing.assert_close(camera_normals_to_light(n, torch.eye(3, dtype=n.dtype)), world_to_light(n))


def test_bad_shapes():
    with pytest.raises(ShapeError, match="v: expected"):
        world_to_light(torch.ones(4))
    with pytest.raises(ShapeError, match="cam_R"):
        camera_normals_to_light(torch.ones(2, 3), torch.eye(2))
