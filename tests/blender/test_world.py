"""World images of SH lights and environment maps (pure torch, no Blender)."""

import math

import pytest
import torch

from relightnet.blender import world_light
from relightnet.blender.frames import latlong_to_equirect
from relightnet.blender.world import envmap_world_image, lift_sh, sh_world_image
from relightnet.checks import InputError, ShapeError
from relightnet.light import ambient_light, directional_light, preset_envmap, preset_light
from relightnet.raster import default_camera, look_at, perspective_camera
from relightnet.render import light_in_world
from relightnet.sh import project_envmap, save_light, sh_to_envmap


def _unroll(img: torch.Tensor) -> torch.Tensor:
    """Blender layout → our lat-long layout (inverse of latlong_to_equirect)."""
    return torch.roll(img, shifts=img.shape[1] // 4, dims=1)


def test_sh_world_image_is_the_exact_reconstruction():
    L = ambient_light((0.4, 0.3, 0.2)) + directional_light((0.3, -0.5, 0.8), (1.0, 0.9, 0.7))
    img, neg, sh = sh_world_image(L, 32)
    assert img.shape == (32, 64, 3) and neg == 0.0 and torch.equal(sh, L)
    assert torch.allclose(_unroll(img), sh_to_envmap(L, 32).float(), atol=1e-5)
    assert torch.allclose(project_envmap(_unroll(img).double(), 2).float(), L, atol=5e-3)


def test_negative_radiance_is_clamped_or_lifted():
    L = preset_light("studio")  # rings below zero at order 2
    img, neg, sh = sh_world_image(L, 32, negative="clamp")
    assert img.min() >= 0 and 0.05 < neg < 0.5 and torch.equal(sh, L)
    lifted, c = lift_sh(L)
    assert (c > 0).all() and torch.allclose(lifted[1:], L[1:])
    assert torch.allclose(lifted[0] - L[0], c * math.sqrt(4 * math.pi))
    img2, neg2, sh2 = sh_world_image(L, 32, negative="lift")
    assert neg2 < 1e-9 and torch.allclose(sh2, lifted)
    assert sh_to_envmap(sh2, 64).min() > -1e-3  # non-negative (up to the grid the minimum was taken on)
    with pytest.raises(InputError):
        sh_world_image(L, 8, negative="abs")


def test_envmap_world_image_rolls_exactly_and_rotates_like_light_in_world():
    env = preset_envmap("sunset")[::8, ::8].contiguous()  # 64 × 128
    assert torch.equal(envmap_world_image(env), latlong_to_equirect(env))
    cam = perspective_camera(look_at(torch.tensor([2.0, 1.5, 2.0]), torch.tensor([0.0, 0.9, 0.0])), 64, fov_deg=30)
    R = cam.R[0].double()
    rotated = _unroll(envmap_world_image(env, R))
    want = light_in_world(project_envmap(env, 2), cam)[0]
    got = project_envmap(rotated, 2)
    assert torch.allclose(got, want, atol=0.03 * float(want.abs().max()))


def test_world_light_kinds_and_frames(tmp_path):
    cam = default_camera(32)
    wl = world_light("sunset", cam)
    assert wl.kind == "envmap" and wl.image.shape == preset_envmap("sunset").shape and wl.source == "sunset"
    assert torch.allclose(wl.sh, preset_light("sunset"), atol=1e-4)
    bl = world_light("sunset", cam, band_limit=True, size=16)
    assert bl.kind == "sh" and bl.image.shape == (16, 32, 3) and bl.negative > 0
    # A camera-relative SH light from a rotated camera is turned into the world frame.
    L = ambient_light(0.3) + directional_light((1.0, 0.0, 0.2), 1.0)
    rot = perspective_camera(look_at(torch.tensor([3.0, 0.85, 0.0]), torch.tensor([0.0, 0.85, 0.0])), 32, fov_deg=35)
    w_cam, w_world = world_light(L, rot, "camera", size=16), world_light(L, rot, "world", size=16)
    assert torch.allclose(w_cam.sh, light_in_world(L, rot)[0], atol=1e-5) and torch.allclose(w_world.sh, L)
    assert not torch.allclose(w_cam.image, w_world.image, atol=1e-2)
    save_light(tmp_path / "l.npz", L)
    assert torch.allclose(world_light(tmp_path / "l.npz", cam, size=16).image, world_light(L, cam, size=16).image)


def test_world_light_bad_inputs(tmp_path):
    with pytest.raises(InputError, match="no_such_light"):
        world_light("no_such_light")
    with pytest.raises(InputError, match="no such environment map"):
        world_light(tmp_path / "missing.exr")
    save_light(tmp_path / "seq.npz", torch.zeros(4, 9, 3))
    with pytest.raises(ShapeError, match="sequence"):
        world_light(tmp_path / "seq.npz")
    with pytest.raises(ShapeError):
        world_light(torch.zeros(8, 3))
    with pytest.raises(InputError, match="light_frame"):
        world_light("studio", default_camera(8), light_frame="view")
