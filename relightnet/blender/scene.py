"""Export a relightnet scene — mesh (still or animated), albedo, light, camera — to a .blend file.

What the file holds (one scene, frames ``1 … T`` = relightnet frames ``0 … T−1``):

- an object ``"avatar"``: the mesh in Blender's frame (:mod:`relightnet.blender.frames`),
  smooth-shaded, with a ``UVMap`` layer (per face corner, from ``uv``/``uv_faces``); a still
  mesh carries relightnet's vertex normals as custom normals, an animation is one shape key
  per frame ``frame_NNNNN`` keyed to weight 1 on its frame only (constant interpolation;
  Blender recomputes the normals of a deformed mesh);
- a material ``"albedo"``: a Diffuse BSDF (Lambertian, roughness 0) whose colour is the
  albedo texture (a packed float EXR, linear, bilinear, edge-clamped — relightnet's texture
  lookup) or a per-vertex colour attribute ``"albedo"``;
- the world: a packed float EXR in the Environment Texture node
  (:mod:`relightnet.blender.world`: the full map, or the lat-long reconstruction of an SH
  light with its negative radiance clamped or lifted), background strength 1;
- a camera equal to relightnet's (:mod:`relightnet.blender.camera`), the output size and
  frame rate (``fps = fps_int / fps_base`` exactly);
- Cycles settings (:func:`relightnet.blender.cycles.configure_cycles`) and a scene property
  ``"relightnet"`` (JSON: light source and kind, frames, the π scale between relightnet and
  Cycles).

The file is written atomically: Blender saves to a hidden temporary file in the target folder
which is renamed over the destination only when everything succeeded.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, ShapeError, check_finite, check_shape
from ..raster import Camera
from ..render.frame import TexturedAlbedo
from ._bpy import quiet, reset
from .camera import SENSOR_WIDTH_MM, blender_camera
from .cycles import configure_cycles
from .frames import world_to_blender
from .settings import CyclesSettings, WorldLightSettings
from .world import WorldLight

logger = logging.getLogger(__name__)

__all__ = ["export_scene", "export_body_scene"]


def _np(x, dtype=np.float32) -> np.ndarray:
    return np.ascontiguousarray(torch.as_tensor(x).detach().cpu().numpy().astype(dtype))


def _fps(fps: float) -> tuple[int, float]:
    if not (np.isfinite(fps) and 0 < fps <= 1000):
        raise InputError(f"fps: expected a frame rate in (0, 1000], got {fps}")
    base = max(1, round(float(fps)))
    return base, base / float(fps)


def _validate(verts, faces, albedo, normals, uv, uv_faces):
    v = torch.as_tensor(verts)
    if v.dim() == 2:
        v = v[None]
    check_shape(v, ["T", "V", 3], name="verts")
    check_finite(v, "verts")
    nv = v.shape[1]
    f = torch.as_tensor(faces).long()
    check_shape(f, ["F", 3], name="faces")
    if f.numel() == 0 or int(f.min()) < 0 or int(f.max()) >= nv:
        raise InputError(f"faces: expected indices in [0, {nv}), got range [{int(f.min())}, {int(f.max())}]")
    if normals is not None:
        check_shape(torch.as_tensor(normals), [nv, 3], name="normals")
    if isinstance(albedo, TexturedAlbedo):
        uv, uv_faces = albedo.uv, albedo.uv_faces
        check_shape(albedo.tex, ["Ht", "Wt", 3], name="albedo.tex")
        check_finite(albedo.tex, "albedo.tex")
    elif albedo is not None:
        check_shape(torch.as_tensor(albedo), [nv, 3], name="albedo")
    if (uv is None) != (uv_faces is None):
        raise InputError("uv and uv_faces: give both or neither")
    if uv is not None:
        check_shape(uv, ["Vt", 2], name="uv")
        check_shape(uv_faces, [f.shape[0], 3], name="uv_faces")
        if int(uv_faces.min()) < 0 or int(uv_faces.max()) >= uv.shape[0]:
            raise InputError(f"uv_faces: expected indices in [0, {uv.shape[0]})")
    return v, f, uv, uv_faces


def _write_exr(path: Path, img: torch.Tensor):
    from ..io import write_envmap

    write_envmap(path, img.float())


def _load_packed(bpy, path: Path, name: str):
    img = bpy.data.images.load(str(path), check_existing=False)
    img.name = name
    img.colorspace_settings.name = "Linear Rec.709"
    img.pack()
    return img


def _mesh_object(bpy, name, verts_b, faces, normals_b, uv_loops):
    me = bpy.data.meshes.new(name)
    nv, nf = verts_b.shape[0], faces.shape[0]
    me.vertices.add(nv)
    me.vertices.foreach_set("co", verts_b.ravel())
    me.loops.add(3 * nf)
    me.loops.foreach_set("vertex_index", faces.astype(np.int32).ravel())
    me.polygons.add(nf)
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * nf, 3, dtype=np.int32))
    me.update(calc_edges=True)
    if uv_loops is not None:
        layer = me.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", uv_loops.ravel())
    me.shade_smooth()
    if normals_b is not None:
        me.normals_split_custom_set_from_vertices(normals_b)
    me.update()
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def _animate(bpy, ob, frames_b: np.ndarray, start: int) -> None:
    """One shape key per frame after the first (the basis), weight 1 on its own frame only."""
    bpy.context.preferences.edit.keyframe_new_interpolation_type = "CONSTANT"
    ob.shape_key_add(name="Basis", from_mix=False)
    n = frames_b.shape[0]
    for t in range(1, n):
        key = ob.shape_key_add(name=f"frame_{t:05d}", from_mix=False)
        key.data.foreach_set("co", frames_b[t].ravel())
        f = start + t
        for frame, value in ((f - 1, 0.0), (f, 1.0), (f + 1, 0.0)):
            if frame <= start + n - 1:
                key.value = value
                key.keyframe_insert("value", frame=frame)
        key.value = 0.0


def _material(bpy, albedo, tex_path: Path | None):
    mat = bpy.data.materials.new("albedo")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Roughness"].default_value = 0.0
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    if tex_path is not None:
        node = nt.nodes.new("ShaderNodeTexImage")
        node.image = _load_packed(bpy, tex_path, "albedo")
        node.interpolation = "Linear"
        node.extension = "EXTEND"
        nt.links.new(node.outputs["Color"], bsdf.inputs["Color"])
    elif albedo is not None:
        node = nt.nodes.new("ShaderNodeVertexColor")
        node.layer_name = "albedo"
        nt.links.new(node.outputs["Color"], bsdf.inputs["Color"])
    else:
        bsdf.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    return mat


def _world(bpy, env_path: Path):
    world = bpy.data.worlds.new("relightnet")
    nt = world.node_tree
    bg = nt.nodes["Background"]
    bg.inputs["Strength"].default_value = 1.0
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = _load_packed(bpy, env_path, "world")
    env.interpolation = "Linear"
    env.projection = "EQUIRECTANGULAR"
    nt.links.new(env.outputs["Color"], bg.inputs["Color"])
    return world


def _camera(bpy, camera: Camera):
    bc = blender_camera(camera)
    cam = bpy.data.cameras.new("camera")
    cam.type = bc.type
    cam.sensor_fit = "HORIZONTAL"
    cam.sensor_width = SENSOR_WIDTH_MM
    cam.lens = bc.lens
    cam.ortho_scale = bc.ortho_scale
    cam.shift_x, cam.shift_y = bc.shift_x, bc.shift_y
    cam.clip_start, cam.clip_end = bc.clip_start, bc.clip_end
    ob = bpy.data.objects.new("camera", cam)
    from mathutils import Matrix  # ships with bpy

    ob.matrix_world = Matrix(bc.matrix_world)  # rows; a plain nested list would be read column-major
    bpy.context.scene.collection.objects.link(ob)
    return ob, bc


def export_scene(
    path,
    verts: torch.Tensor,
    faces: torch.Tensor,
    light: WorldLight,
    camera: Camera,
    albedo: TexturedAlbedo | torch.Tensor | None = None,
    normals: torch.Tensor | None = None,
    uv: torch.Tensor | None = None,
    uv_faces: torch.Tensor | None = None,
    fps: float = 30.0,
    cycles: CyclesSettings = CyclesSettings(),
    metadata: Mapping | None = None,
) -> Path:
    """Write a Blender scene of a (possibly animated) mesh lit by a world light (module docstring).

    Args:
        path: destination ``.blend`` (its folder must exist); replaced atomically.
        verts: (V, 3) or (T, V, 3) world-frame positions (relightnet frame, y up).
        faces: (F, 3) triangles, counter-clockwise seen from outside.
        light: a :class:`~relightnet.blender.world.WorldLight` (see :func:`world_light`),
            already in the world frame for this camera.
        camera: one relightnet camera (intrinsics, extrinsics, image size).
        albedo: a :class:`~relightnet.render.TexturedAlbedo` (linear texture and its UVs),
            (V, 3) linear per-vertex albedo, or None (grey 0.5).
        normals: (V, 3) vertex normals of a still mesh (kept as custom normals).
        uv, uv_faces: (Vt, 2), (F, 3) UVs when ``albedo`` is not a texture (optional).
        fps: frame rate. cycles: the file's Cycles samples and diffuse bounces
            (:class:`~relightnet.blender.CyclesSettings`; its threads are the renderer's, not the file's).
        metadata: extra JSON-able items for the scene's ``"relightnet"`` property.

    Returns:
        The path written.

    Raises:
        InputError / ShapeError: bad arguments (nothing is written).
    """
    path = Path(path)
    if path.suffix.lower() != ".blend":
        raise InputError(f"{path}: expected an output file ending in .blend")
    if not path.parent.is_dir():
        raise InputError(f"{path}: output folder {path.parent} does not exist")
    if not isinstance(light, WorldLight):
        raise InputError(f"light: expected a WorldLight (relightnet.blender.world_light), got {type(light).__name__}")
    v, f, uv, uv_faces = _validate(verts, faces, albedo, normals, uv, uv_faces)
    fps_int, fps_base = _fps(fps)
    blender_camera(camera)  # validate before touching Blender
    n_frames = v.shape[0]
    uv_loops = None if uv is None else _np(torch.as_tensor(uv)[torch.as_tensor(uv_faces).long()].reshape(-1, 2))
    mesh = {"verts_b": _np(world_to_blender(v.double())), "faces": _np(f, np.int64), "uv_loops": uv_loops,
            "normals_b": (_np(world_to_blender(torch.as_tensor(normals).double()))
                          if normals is not None and n_frames == 1 else None)}
    meta = {
        "frames": n_frames, "frame_start": 1, "fps": float(fps), "light_source": light.source,
        "light_kind": light.kind, "light_negative_fraction": light.negative,
        "light_sh_world": light.sh.tolist(), "frame_map": "blender (x, y, z) = relightnet (x, -z, y)",
        "radiometry": "relightnet pixel = pi * Cycles pixel (diffuse BSDF, same world)",
    }
    meta.update(dict(metadata or {}))

    def build(bpy, tdir: Path) -> None:
        scene = _build_scene(bpy, tdir, mesh, albedo, light, camera)
        scene.render.fps, scene.render.fps_base = fps_int, fps_base
        scene.frame_start, scene.frame_end = 1, n_frames
        scene.frame_set(1)
        configure_cycles(scene, spp=cycles.spp, bounces=cycles.bounces, denoise=False)
        scene["relightnet"] = json.dumps(meta)

    _save_blend(path, build)
    logger.info("wrote %s (%d frame%s, %s world)", path, n_frames, "s" if n_frames > 1 else "", light.kind)
    return path


def _build_scene(bpy, tdir: Path, mesh: dict, albedo, light: WorldLight, camera: Camera):
    """The mesh (animated when it has several frames), its material, the world and the camera in
    Blender's current (empty) scene; texture and world images are written into ``tdir``."""
    tex_path = None
    if isinstance(albedo, TexturedAlbedo):
        tex_path = tdir / "albedo.exr"
        _write_exr(tex_path, torch.as_tensor(albedo.tex).clamp(0, 1))
    env_path = tdir / "world.exr"
    _write_exr(env_path, light.image)
    scene = bpy.context.scene
    scene.name = "relightnet"
    verts_b = mesh["verts_b"]
    ob = _mesh_object(bpy, "avatar", verts_b[0], mesh["faces"], mesh["normals_b"], mesh["uv_loops"])
    if albedo is not None and not isinstance(albedo, TexturedAlbedo):
        attr = ob.data.color_attributes.new("albedo", "FLOAT_COLOR", "POINT")
        rgba = np.concatenate([_np(albedo), np.ones((verts_b.shape[1], 1), np.float32)], axis=1)
        attr.data.foreach_set("color", rgba.ravel())
    ob.data.materials.append(_material(bpy, albedo, tex_path))
    if verts_b.shape[0] > 1:
        _animate(bpy, ob, verts_b, 1)
    scene.world = _world(bpy, env_path)
    cam_ob, bc = _camera(bpy, camera)
    scene.camera = cam_ob
    scene.render.resolution_x, scene.render.resolution_y = bc.resolution
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    return scene


def _save_blend(path: Path, build) -> None:
    """Reset Blender, ``build(bpy, tmp folder)`` the scene, save it compressed to a temporary file beside
    ``path`` and move it into place (nothing is left behind on failure)."""
    bpy = reset()
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".tmp.blend")
    os.close(fd)
    os.unlink(tmp)  # a unique name; Blender would keep an existing file as a ".blend1" backup
    bpy.context.preferences.filepaths.save_version = 0
    try:
        with tempfile.TemporaryDirectory() as tdir:
            build(bpy, Path(tdir))
            with quiet((1,)):
                bpy.ops.wm.save_as_mainfile(filepath=tmp, check_existing=False, compress=True, copy=True)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def export_body_scene(
    path,
    body,
    params: Mapping,
    light,
    albedo=None,
    camera: Camera | str | None = None,
    size=512,
    fps: float = 30.0,
    world: WorldLightSettings = WorldLightSettings(),
    cycles: CyclesSettings = CyclesSettings(),
) -> Path:
    """Pose a body model (one frame or a motion) and export it with :func:`export_scene`.

    Args:
        path: destination ``.blend``.
        body: a :class:`~relightnet.body.BodyModel`.
        params: its parameters, with a leading frame axis T for a motion.
        light: any light :func:`relightnet.blender.world_light` takes (camera-relative by default).
        albedo: TexturedAlbedo / (V, 3) / None (Anny's default outfit, grey 0.6 otherwise).
        camera: one camera, None (:func:`relightnet.raster.default_camera` of ``size``) or
            ``"fit"`` (:func:`relightnet.render.jobs.fit_camera` framing every frame of the motion).
        world: the :func:`world_light` options (:class:`~relightnet.blender.WorldLightSettings`).
        fps, cycles: :func:`export_scene` options.

    Returns:
        The path written.
    """
    from ..body import AnnyBody, default_albedo
    from ..raster import default_camera
    from ..render.jobs import fit_camera
    from .world import world_light

    with torch.no_grad():
        out = body(params)
    if camera is None:
        camera = default_camera(size)
    elif isinstance(camera, str):
        if camera != "fit":
            raise InputError(f"camera: expected a Camera, None or 'fit', got {camera!r}")
        camera = fit_camera(out.verts.reshape(-1, 3), size)
    wl = world_light(light, camera, world.light_frame, world.band_limit, world.lmax, world.size, world.negative)
    if albedo is None:
        if isinstance(body, AnnyBody):
            a = default_albedo(body)
            albedo = TexturedAlbedo(a.texture, body.uv, body.uv_faces)
        else:
            albedo = torch.full((body.num_verts, 3), 0.6)
    if isinstance(albedo, torch.Tensor) and albedo.shape != (out.verts.shape[1], 3):
        raise ShapeError(f"albedo: expected ({out.verts.shape[1]}, 3), got {tuple(albedo.shape)}")
    normals = out.normals[0] if out.batch_size == 1 else None
    return export_scene(path, out.verts, out.faces, wl, camera, albedo=albedo, normals=normals, uv=out.uv,
                        uv_faces=out.uv_faces, fps=fps, cycles=cycles,
                        metadata={"light_frame": world.light_frame, "band_limit": bool(world.band_limit)})
