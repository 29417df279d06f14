"""Whole rendering jobs of the 3D path: any mesh file, or the Anny/SMPL body (still or moving).

Each job is a function first (used by the CLI, the data generator and the demo).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..body.base import vertex_normals
from ..checks import InputError, sh_order_from_count
from ..io.documents import clip
from ..prt import PrtSettings, check_mesh, vertex_transport
from ..raster import Camera, Window, default_camera, look_at, perspective_camera, rasterize, screen_box
from .frame import RenderOutput, TexturedAlbedo, render_mesh

logger = logging.getLogger(__name__)

__all__ = ["LoadedMesh", "load_mesh", "fit_camera", "render_mesh_file", "BodyFrame", "frame_slice",
           "render_body_frames"]


@dataclass(frozen=True, eq=False)
class LoadedMesh:
    """A triangle mesh read from a file: verts (V, 3), faces (F, 3) int64, normals (V, 3), albedo (V, 3)."""

    verts: torch.Tensor
    faces: torch.Tensor
    normals: torch.Tensor
    albedo: torch.Tensor


def load_mesh(path, albedo=(0.8, 0.8, 0.8)) -> LoadedMesh:
    """Load any mesh trimesh reads (OBJ, PLY, GLB, STL, OFF, ...), assumed y-up.

    Vertex colours in the file become the albedo (sRGB → linear); otherwise ``albedo``.
    The file is bounded before it is parsed (:mod:`relightnet.io.meshfile`: size, face count,
    referenced files regular and inside its folder).
    """
    import trimesh

    from ..io.meshfile import check_face_count, check_mesh_file, mesh_resolver

    path = Path(path)
    used = check_mesh_file(path)
    try:
        m = trimesh.load(path, force="mesh", process=True, resolver=mesh_resolver(path, used))
    except InputError:
        raise
    except Exception as e:  # trimesh raises many types for bad files
        raise InputError(f"{path}: unreadable mesh ({type(e).__name__}: {clip(str(e))})") from None
    if not isinstance(m, trimesh.Trimesh) or len(m.faces) == 0:
        raise InputError(f"{path}: expected a triangle mesh with at least one face")
    check_face_count(len(m.faces), path)
    v = torch.as_tensor(np.asarray(m.vertices), dtype=torch.float32)
    f = torch.as_tensor(np.asarray(m.faces), dtype=torch.int64)
    alb = torch.tensor(albedo, dtype=torch.float32).expand(len(v), 3).clone()
    colors = getattr(m.visual, "vertex_colors", None) if m.visual.kind == "vertex" else None
    if colors is not None and len(colors) == len(v):
        from ..color import srgb_to_linear

        alb = srgb_to_linear(torch.as_tensor(np.asarray(colors)[:, :3] / 255.0, dtype=torch.float32))
    return LoadedMesh(v, f, vertex_normals(v, f), alb.clamp(0.0, 1.0))


def fit_camera(verts: torch.Tensor, size, fov_deg: float = 35.0, margin: float = 1.1,
               elevation_deg: float = 20.0) -> Camera:
    """A camera in front (+z) of the mesh, raised by ``elevation_deg``, looking at its
    bounding-sphere centre and framing it whole.

    Args:
        verts: (V, 3) world positions.
        size: (H, W) or int.
    """
    lo, hi = verts.amin(0), verts.amax(0)
    centre, radius = (lo + hi) / 2, ((hi - lo).norm() / 2).clamp_min(1e-6)
    half = math.radians(fov_deg) / 2
    dist = float(radius) * margin / math.sin(half)
    el = math.radians(elevation_deg)
    eye = centre + dist * torch.tensor([0.0, math.sin(el), math.cos(el)])
    return perspective_camera(look_at(eye, centre), size, fov_deg=fov_deg, near=max(dist - 2 * float(radius), 1e-3) / 2,
                              far=dist + 4 * float(radius))


def render_mesh_file(path, light: torch.Tensor, size=512, prt: PrtSettings = PrtSettings(),
                     albedo=(0.8, 0.8, 0.8)) -> RenderOutput:
    """Render a mesh file under an SH light with PRT transport (the seed's teapot demo).

    The light is fixed to the world (an environment around the mesh), seen from a camera
    raised 20° above the horizon so that ground shadows show.

    Args:
        path: mesh file.
        light: (K, 3) SH light in the world's light frame.
        size: output (H, W) or int.
        prt: the PRT options (:class:`relightnet.prt.PrtSettings`).

    Returns:
        :class:`RenderOutput` with maps.
    """
    mesh = load_mesh(path, albedo)
    lmax = sh_order_from_count(light.shape[-2], "light")
    T = vertex_transport(mesh.verts, mesh.faces, mesh.normals, lmax=lmax, prt=prt,
                         albedo=mesh.albedo if prt.bounces else None)
    return render_mesh(mesh.verts, mesh.faces, T, mesh.albedo, light, fit_camera(mesh.verts, size),
                       normals=mesh.normals, light_frame="world", maps=True)


def _visible(camera: Camera, verts: torch.Tensor, faces: torch.Tensor, box: bool, seen: bool):
    """What :func:`render_body_frames` renders a pose with: ``(window, frags, seen vertices)``, each None
    unless asked for. The window (``box``): the (V, 3) mesh's screen box padded by 2 pixels
    (antialiasing looks one pixel beyond the silhouette), or, when nothing of it can be on screen, the
    frame's top-left pixel (which it does not cover). The fragments and the vertices they show (``seen``):
    to compute the transport at those vertices only."""
    if not (box or seen):
        return None, None, None
    vc = camera.transform(verts)
    win = None
    if box:
        win = screen_box(vc, faces, camera.size, pad=2)
        win = Window(0, 0, 1, 1, camera.size) if win is None else win
    if not seen:
        return win, None, None
    frags = rasterize(vc, faces, camera.size, window=win)
    return win, frags, frags.seen_vertices(faces, verts.shape[0])


@dataclass(frozen=True, eq=False)
class BodyFrame:
    """One rendered body frame: its index, the render, the per-vertex transport (V, K[, 3]) and
    the posed vertices (V, 3) (world frame)."""

    index: int
    render: RenderOutput
    transport: torch.Tensor
    verts: torch.Tensor | None = None


def frame_slice(params, a: int, b: int, n: int):
    """Frames a..b of body parameters with n frames: tensors with ≥ 2 dims and n rows are
    sliced (recursively in mappings), the others (shape, phenotype) kept."""
    if isinstance(params, Mapping):
        return {k: frame_slice(v, a, b, n) for k, v in params.items()}
    if isinstance(params, torch.Tensor) and params.dim() >= 2 and params.shape[0] == n:
        return params[a:b]
    return params


def render_body_frames(
    body,
    params: Mapping,
    light: torch.Tensor,
    albedo: torch.Tensor | TexturedAlbedo,
    camera: Camera | int | tuple[int, int] | None = 512,
    prt: PrtSettings = PrtSettings(n_dirs=64),
    maps: bool = False,
    vertex_albedo: torch.Tensor | None = None,
    n_frames: int | None = None,
    chunk: int = 16,
    visible_only: bool = False,
    box: bool = False,
) -> Iterator[BodyFrame]:
    """Pose a body model and render it frame by frame (streaming: one frame in memory at a time).

    Args:
        body: a :class:`~relightnet.body.BodyModel` (Anny or SMPL).
        params: body parameters with a leading frame axis T (e.g. ``make_motion(...)`` output or
            ``Motion.body_params()``), or without it for a single frame.
        light: (K, 3) for all frames or (T, K, 3) per frame, relative to the camera.
        albedo: (V, 3) per-vertex albedo or a :class:`TexturedAlbedo`.
        camera: one camera, or the image size (H, W) or int of the
            :func:`relightnet.raster.default_camera` to use (None: 512).
        prt: the PRT options (:class:`relightnet.prt.PrtSettings`; transport is recomputed per
            pose); by default 64 directions.
        maps: also produce the transport/albedo/normal/depth maps.
        vertex_albedo: (V, 3) albedo for interreflection when ``albedo`` is a texture
            (default: ``albedo`` itself when per-vertex, else 0.5 grey).
        n_frames: T when ``params`` has a frame axis: the body is then posed ``chunk`` frames at
            a time (tensors with ≥ 2 dims and T rows are sliced), so memory does not grow with T.
            None poses all frames at once.
        visible_only: compute the transport only at the vertices of faces the camera sees
            (the image is the same; ``BodyFrame.transport`` is 0 elsewhere). About twice as
            fast for a body; ignored with ``bounces`` (which need every vertex).
        box: render only the body's box on screen (its :func:`~relightnet.raster.screen_box`, padded
            by 2 pixels; the top-left pixel when none of it is on screen): the render's images are
            the window's size (``render.frags.window`` says where it lies), the same pixels as the
            whole frame's. The memory of a frame then follows the body's size on screen, not the
            frame's.

    Yields:
        :class:`BodyFrame` per frame.
    """
    camera = camera if isinstance(camera, Camera) else default_camera(512 if camera is None else camera)
    if n_frames is not None and (isinstance(n_frames, bool) or int(n_frames) < 1 or int(chunk) < 1):
        raise InputError(f"n_frames, chunk: expected integers >= 1, got {n_frames}, {chunk}")

    # Grad mode is switched off around the work, never across a yield: a generator suspended inside
    # ``torch.no_grad()`` leaves it off in its consumer, and two of them interleaved restore each
    # other's state in the wrong order (grad mode stayed off after such a pair).
    def posed():
        for a in range(0, 1 if n_frames is None else n_frames, chunk):
            with torch.no_grad():
                out = body(params if n_frames is None else frame_slice(params, a, min(a + chunk, n_frames), n_frames))
            yield out

    lmax = sh_order_from_count(light.shape[-2], "light")
    bounce_albedo = vertex_albedo if vertex_albedo is not None else albedo if isinstance(albedo, torch.Tensor) else None
    t = 0
    n = n_frames
    for out in posed():
        if t == 0:  # the topology is the body's, the same in every pose: checked once (it may warn)
            check_mesh(out.verts[0], out.faces)
        n = out.batch_size if n is None else n
        if light.dim() == 3 and light.shape[0] not in (1, n):
            raise InputError(f"light: a light sequence has {light.shape[0]} frames but the motion has {n}")
        for i in range(out.batch_size):
            v, nrm = out.verts[i], out.normals[i]
            L = light[t if light.shape[0] == n else 0] if light.dim() == 3 else light
            with torch.no_grad():
                win, frags, seen = _visible(camera, v, out.faces, box, visible_only and not prt.bounces)
                T = vertex_transport(v, out.faces, nrm, lmax=lmax, prt=prt, albedo=bounce_albedo, vertices=seen,
                                     manifold="ignore")
                r = render_mesh(v, out.faces, T, albedo, L, camera, normals=nrm, maps=maps, frags=frags, window=win)
            yield BodyFrame(t, r, T, v)
            del r, T, frags  # the next frame is rendered without this one's (a frame at the pixel limit: ~0.5 GB)
            t += 1
