"""Export → reopen the .blend with bpy: mesh, UVs, material, world image, camera, animation; bad inputs."""

import json

import numpy as np
import pytest
import torch

from relightnet.blender import WorldLightSettings, export_body_scene, export_scene, world_light, world_to_blender
from relightnet.blender.camera import blender_camera
from relightnet.blender.cycles import open_blend, read_image_pixels
from relightnet.body import default_albedo, make_motion
from relightnet.checks import InputError, ShapeError
from relightnet.raster import default_camera
from relightnet.render import TexturedAlbedo


@pytest.fixture(scope="module")
def albedo(anny_body):
    a = default_albedo(anny_body, texture_size=64)
    return TexturedAlbedo(a.texture, anny_body.uv, anny_body.uv_faces)


def _get(collection, attr, n, width):
    buf = np.empty(n * width, dtype=np.float32)
    collection.foreach_get(attr, buf)
    return buf.reshape(n, width)


def test_still_avatar_round_trip(tmp_path, anny_body, albedo):
    cam = default_camera((48, 40))
    params = {"pose": anny_body.pose("arms_crossed")}
    path = export_body_scene(tmp_path / "a.blend", anny_body, params, "sunset", albedo=albedo, camera=cam, fps=24)
    assert path.is_file() and sorted(p.name for p in tmp_path.iterdir()) == ["a.blend"]
    out = anny_body(params)
    wl = world_light("sunset", cam)

    scene = open_blend(path)
    ob = scene.objects["avatar"]
    me = ob.data
    V, F = out.verts.shape[1], out.faces.shape[0]
    assert (len(me.vertices), len(me.polygons), len(me.loops)) == (V, F, 3 * F) == (13718, 27420, 82260)
    co = _get(me.vertices, "co", V, 3)
    assert np.allclose(co, world_to_blender(out.verts[0].double()).numpy(), atol=1e-6)
    loops = _get(me.loops, "vertex_index", 3 * F, 1).astype(np.int64).reshape(F, 3)
    assert np.array_equal(loops, out.faces.numpy())
    uv = _get(me.uv_layers["UVMap"].data, "uv", 3 * F, 2)
    assert np.allclose(uv, out.uv[out.uv_faces].reshape(-1, 2).numpy(), atol=1e-6)
    # Custom normals are ours (Blender stores them compressed: a fraction of a degree).
    nrm = _get(me.corner_normals, "vector", 3 * F, 3)
    want = world_to_blender(out.normals[0].double())[out.faces.reshape(-1)].numpy()
    assert np.degrees(np.arccos(np.clip((nrm * want).sum(1), -1, 1))).max() < 1.0

    mat = me.materials[0]
    kinds = {n.bl_idname for n in mat.node_tree.nodes}
    assert {"ShaderNodeBsdfDiffuse", "ShaderNodeTexImage", "ShaderNodeOutputMaterial"} <= kinds
    tex = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeTexImage")
    assert tex.image.packed_file is not None and tex.image.colorspace_settings.name == "Linear Rec.709"
    assert tex.extension == "EXTEND" and tex.interpolation == "Linear"
    assert np.allclose(read_image_pixels(tex.image)[..., :3], albedo.tex.numpy(), atol=1e-6)
    bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfDiffuse")
    assert bsdf.inputs["Color"].links[0].from_node == tex

    env = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeTexEnvironment")
    assert env.image.packed_file is not None and env.projection == "EQUIRECTANGULAR"
    assert np.array_equal(read_image_pixels(env.image)[..., :3], wl.image.numpy())

    bc = blender_camera(cam)
    c = scene.camera
    assert c.data.lens == pytest.approx(bc.lens) and c.data.sensor_fit == "HORIZONTAL"
    assert (c.data.shift_x, c.data.shift_y) == pytest.approx((bc.shift_x, bc.shift_y), abs=1e-7)
    assert np.allclose(np.array(c.matrix_world), np.array(bc.matrix_world), atol=1e-6)
    r = scene.render
    assert (r.resolution_x, r.resolution_y, r.resolution_percentage) == (40, 48, 100)
    assert r.fps / r.fps_base == pytest.approx(24.0) and (scene.frame_start, scene.frame_end) == (1, 1)
    assert scene.cycles.device == "CPU" and scene.cycles.samples == 64 and not scene.cycles.use_denoising
    meta = json.loads(scene["relightnet"])
    assert meta["light_kind"] == "envmap" and meta["frames"] == 1 and "pi" in meta["radiometry"]


def test_animation_is_one_shape_key_per_frame(tmp_path, anny_body, albedo):
    import bpy

    params = make_motion("walk", 3, fps=29.97)
    path = export_body_scene(tmp_path / "w.blend", anny_body, params, "studio", albedo=albedo, size=32,
                             fps=29.97, camera="fit", world=WorldLightSettings(band_limit=True, size=16))
    out = anny_body(params)
    scene = open_blend(path)
    assert (scene.frame_start, scene.frame_end) == (1, 3)
    assert scene.render.fps / scene.render.fps_base == pytest.approx(29.97)
    ob = scene.objects["avatar"]
    assert [k.name for k in ob.data.shape_keys.key_blocks] == ["Basis", "frame_00001", "frame_00002"]
    env = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeTexEnvironment")
    assert tuple(env.image.size) == (32, 16)
    for t in range(3):
        scene.frame_set(1 + t)
        ev = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
        me = ev.to_mesh()
        co = _get(me.vertices, "co", len(me.vertices), 3)
        ev.to_mesh_clear()
        assert np.allclose(co, world_to_blender(out.verts[t].double()).numpy(), atol=1e-5), t
    assert not np.allclose(out.verts[0], out.verts[2], atol=1e-3)  # the frames do differ


def test_vertex_albedo_and_sh_light(tmp_path):
    import trimesh

    m = trimesh.creation.icosphere(1)
    v = torch.tensor(m.vertices, dtype=torch.float32)
    f = torch.tensor(m.faces)
    alb = torch.rand(len(v), 3)
    wl = world_light(torch.eye(9, 3), default_camera(16), size=8)
    export_scene(tmp_path / "s.blend", v, f, wl, default_camera(16), albedo=alb)
    scene = open_blend(tmp_path / "s.blend")
    me = scene.objects["avatar"].data
    col = _get(me.color_attributes["albedo"].data, "color", len(v), 4)
    assert np.allclose(col[:, :3], alb.numpy(), atol=1e-6) and len(me.uv_layers) == 0
    assert json.loads(scene["relightnet"])["light_kind"] == "sh"


def test_bad_inputs_leave_no_blend(tmp_path, anny_body):
    cam = default_camera(16)
    v, f = torch.rand(4, 3), torch.tensor([[0, 1, 2], [0, 2, 3]])
    wl = world_light(torch.eye(9, 3), cam, size=8)
    with pytest.raises(InputError, match="not a light file or preset"):
        export_body_scene(tmp_path / "a.blend", anny_body, {}, "no_such_light", camera=cam)
    with pytest.raises(InputError, match="texture file not found"):
        from relightnet.pipeline.scene import avatar_albedo

        avatar_albedo(anny_body, str(tmp_path / "missing.png"))
    with pytest.raises(InputError, match="motion kind"):
        make_motion("moonwalk", 3)
    with pytest.raises(ShapeError, match="albedo"):
        export_scene(tmp_path / "a.blend", v, f, wl, cam, albedo=torch.rand(5, 3))
    with pytest.raises(InputError, match="faces"):
        export_scene(tmp_path / "a.blend", v, torch.tensor([[0, 1, 9]]), wl, cam)
    with pytest.raises(InputError, match=".blend"):
        export_scene(tmp_path / "a.obj", v, f, wl, cam)
    with pytest.raises(InputError, match="WorldLight"):
        export_scene(tmp_path / "a.blend", v, f, "studio", cam)
    with pytest.raises(InputError, match="does not exist"):
        export_scene(tmp_path / "no" / "a.blend", v, f, wl, cam)
    assert list(tmp_path.iterdir()) == []


def test_failure_inside_blender_leaves_nothing(tmp_path, monkeypatch):
    """An error while Blender builds or saves the scene removes the temporary file."""
    import relightnet.blender.scene as scene_mod

    def boom(*a, **k):
        raise RuntimeError("disk full")

    monkeypatch.setattr(scene_mod, "configure_cycles", boom)
    wl = world_light(torch.eye(9, 3), default_camera(16), size=8)
    with pytest.raises(RuntimeError, match="disk full"):
        export_scene(tmp_path / "a.blend", torch.rand(3, 3), torch.tensor([[0, 1, 2]]), wl, default_camera(16))
    assert list(tmp_path.iterdir()) == []
