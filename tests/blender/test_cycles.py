"""Cycles renders: the sphere test (scale π, light orientation) and the frame writer."""

import math

import pytest
import torch

from relightnet.blender import export_scene, render_blend, world_light
from relightnet.blender.cycles import CYCLES_TO_RELIGHTNET
from relightnet.blender.reference import masked_rel_rmse
from relightnet.body.base import vertex_normals
from relightnet.checks import InputError
from relightnet.io import read_envmap, read_image
from relightnet.light import ambient_light, directional_light
from relightnet.prt import PrtSettings, vertex_transport
from relightnet.raster import look_at, perspective_camera
from relightnet.render import render_mesh
from relightnet.sh import rotate_sh, sh_to_envmap

#: 64², 8 spp: Cycles' noise alone is ≈ 8 % relative RMSE (0.2 % at 256 spp, measured); the mean
#: over the sphere is within 0.3 % of ours. A light turned 90° gives 37 %.
RMSE_TOL, MEAN_TOL = 0.13, 0.03


def _sphere():
    import trimesh

    m = trimesh.creation.icosphere(3)
    v = torch.tensor(m.vertices, dtype=torch.float32) * 0.5 + torch.tensor([0.0, 0.85, 0.0])
    f = torch.tensor(m.faces, dtype=torch.int64)
    return v, f, vertex_normals(v, f)


@pytest.fixture(scope="module")
def sphere_case(tmp_path_factory):
    """An unoccluded sphere seen from a rotated camera under a non-negative band-limited camera-relative light."""
    tmp = tmp_path_factory.mktemp("sphere")
    v, f, n = _sphere()
    L = ambient_light((0.3, 0.25, 0.2)) + directional_light((1.0, 0.6, 0.8), (1.0, 0.8, 0.6))
    assert sh_to_envmap(L, 64).min() > 0  # no clamping: Cycles sees exactly this band-limited world
    cam = perspective_camera(look_at(torch.tensor([1.5, 1.8, 2.2]), torch.tensor([0.0, 0.85, 0.0])), 64, fov_deg=30)
    alb = torch.tensor([0.7, 0.6, 0.5]).expand(len(v), 3).contiguous()
    T = vertex_transport(v, f, n, prt=PrtSettings(occlusion=False, n_dirs=1024))
    ours = render_mesh(v, f, T, alb, L, cam)  # light_frame="camera", as in the avatar pipeline
    export_scene(tmp / "s.blend", v, f, world_light(L, cam, size=64), cam, albedo=alb, normals=n)
    frames = list(render_blend(tmp / "s.blend", tmp / "out", spp=8, bounces=0, filter_width=0.01))
    return dict(v=v, f=f, T=T, alb=alb, L=L, cam=cam, ours=ours, frames=frames, tmp=tmp)


def test_sphere_agrees_with_our_unoccluded_render(sphere_case):
    ours, (fr,) = sphere_case["ours"], sphere_case["frames"]
    cy = fr.rgba
    assert cy.shape == (64, 64, 4)
    a, b = ours.alpha[0] > 0.5, cy[..., 3] > 0.5
    assert (a & b).sum() / (a | b).sum() > 0.99  # same silhouette: same camera
    mask = a & b & (cy[..., 3] > 0.999)
    mine = ours.image[0] / CYCLES_TO_RELIGHTNET
    assert masked_rel_rmse(mine, cy[..., :3], mask) < RMSE_TOL
    ratio = mine[mask].sum(0) / cy[..., :3][mask].sum(0)
    assert torch.allclose(ratio, torch.ones(3), atol=MEAN_TOL), ratio  # relightnet = π × Cycles


def test_sphere_test_detects_a_wrong_light_orientation(sphere_case):
    """The same comparison with the light turned 90° about the up axis, or not made camera-relative, fails."""
    c, (fr,) = sphere_case, sphere_case["frames"]
    quarter = torch.tensor([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # about z_light = up
    wrong = render_mesh(c["v"], c["f"], c["T"], c["alb"], rotate_sh(c["L"], quarter), c["cam"])
    mask = (wrong.alpha[0] > 0.5) & (fr.rgba[..., 3] > 0.999)
    assert masked_rel_rmse(wrong.image[0] / math.pi, fr.rgba[..., :3], mask) > 2 * RMSE_TOL  # measured 37 %
    # Forgetting that the light is camera-relative (the camera is rotated) fails too (measured 21 %).
    fixed = render_mesh(c["v"], c["f"], c["T"], c["alb"], c["L"], c["cam"], light_frame="world")
    assert masked_rel_rmse(fixed.image[0] / math.pi, fr.rgba[..., :3], mask) > 1.4 * RMSE_TOL


def test_render_blend_writes_exr_and_png(sphere_case):
    (fr,) = sphere_case["frames"]
    out = sphere_case["tmp"] / "out"
    assert sorted(p.name for p in out.iterdir()) == ["frame_00000.exr", "frame_00000.png"]
    assert fr.exr == out / "frame_00000.exr" and fr.index == 0 and fr.seconds > 0
    assert torch.allclose(read_envmap(fr.exr), fr.rgba[..., :3].clamp_min(0))
    png = read_image(fr.png)
    assert png.shape == (64, 64, 3) and png.max() > 0.8 and png[0, 0].max() == 0  # auto exposure, black background


def test_render_blend_bad_inputs(sphere_case, tmp_path):
    with pytest.raises(InputError, match="no such .blend"):
        next(render_blend(tmp_path / "missing.blend"))
    (tmp_path / "junk.blend").write_bytes(b"not a blend file")
    with pytest.raises(InputError, match="cannot open"):
        next(render_blend(tmp_path / "junk.blend"))
    with pytest.raises(InputError, match="frames"):
        next(render_blend(sphere_case["tmp"] / "s.blend", tmp_path / "o", frames=(1, 3)))
    with pytest.raises(InputError, match="spp"):
        next(render_blend(sphere_case["tmp"] / "s.blend", spp=0))
    assert not (tmp_path / "o").exists()


def test_render_settings_of_a_blend_are_bounded(monkeypatch):
    """A .blend asking 20000² × 16.7 M samples × 10⁶ frames is refused before Blender renders
    (the check takes the scene's numbers; the pixel limit is --max-pixels')."""
    from relightnet.blender.cycles import MAX_FRAMES, MAX_SAMPLES, check_render_settings

    check_render_settings("a.blend", 1920, 1080, 100, 128, 300)
    with pytest.raises(InputError, match="a.blend: render output: 20000x20000 pixels"):
        check_render_settings("a.blend", 20000, 20000, 100, 16_777_216, 1_000_000)
    check_render_settings("a.blend", 20000, 20000, 10, 64, 1)  # resolution_percentage 10: 2000²
    monkeypatch.setenv("RELIGHTNET_MAX_PIXELS", "1000")
    with pytest.raises(InputError, match="above the limit"):
        check_render_settings("a.blend", 64, 64, 100, 64, 1)
    monkeypatch.delenv("RELIGHTNET_MAX_PIXELS")
    with pytest.raises(InputError, match="16777216 Cycles samples"):
        check_render_settings("a.blend", 64, 64, 100, 16_777_216, 1)
    with pytest.raises(InputError, match="1000000 frames"):
        check_render_settings("a.blend", 64, 64, 100, MAX_SAMPLES, 1_000_000)
    check_render_settings("a.blend", 64, 64, 100, MAX_SAMPLES, MAX_FRAMES)
    check_render_settings("a.blend", 1200, 1200, 100, 64, 1, denoise=True)  # 1.44 MP: denoised
    with pytest.raises(InputError, match=r"a\.blend: denoising a 2000x2000 render \(4\.0 MP\) takes about 3\.4 GiB"):
        check_render_settings("a.blend", 2000, 2000, 100, 64, 1, denoise=True)
    check_render_settings("a.blend", 2000, 2000, 100, 64, 1)  # not denoised: within the pixel limit


def test_what_a_killed_render_left_is_removed_by_the_next_render(tmp_path):
    """A frame Blender saved under its temporary name but that was never renamed, and the staging folder of
    an older version, both of a writer that is gone, are removed by the next render into the same folder.
    (A render killed mid-frame leaves nothing at all: ``test_cycles_hostile.py``.)"""
    import os

    from relightnet.io.atomic import temp_path
    from tests.blender.hostile_blends import write_blend

    blend = write_blend(tmp_path / "s.blend", side=16, samples=1)
    out = tmp_path / "out"
    out.mkdir()
    frame, stage = temp_path(out / "frame_00000.exr", "render"), temp_path(out / "frames", "stage")
    gone = [p.with_name(p.name.replace(f".{os.getpid()}-", ".999999999-")) for p in (frame, stage)]
    gone[0].write_bytes(b"half an EXR")
    gone[1].mkdir()
    assert len(list(render_blend(blend, out))) == 1
    assert sorted(p.name for p in out.iterdir()) == ["frame_00000.exr", "frame_00000.png"]
