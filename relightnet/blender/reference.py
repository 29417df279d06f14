"""relightnet's PRT render against a Cycles path-traced reference, for one avatar frame.

Two Cycles references of the same scene (same mesh, normals, texture, camera):

- the **SH-band-limited world** — the order-``lmax`` reconstruction of the environment map,
  lifted by the smallest constant that makes it non-negative (Cycles clamps negative
  radiance); relightnet renders the *same* lifted coefficients, so the difference is PRT's
  own error (direction quadrature, per-vertex interpolation of visibility and
  interreflection) plus Cycles' noise;
- the **full environment map** — relightnet renders the plain order-``lmax`` projection,
  so the difference adds what order-2 SH loses (sharp shadows, the sun's highlight shape).

Cycles runs with as many diffuse bounces as the PRT render (0 = direct light with
shadows), camera rays through pixel centres (filter width 0.01, as relightnet's
rasterizer samples) and no denoising. relightnet's image is divided by π
(:data:`relightnet.blender.cycles.CYCLES_TO_RELIGHTNET`).

Metric: masked relative RMSE ``‖a − b‖₂ / ‖b‖₂`` over the pixels covered in both renders
(RGB per pixel), eroded by ``erode`` pixels; a second value also leaves out pixels whose
interpolated normal faces away from the camera (silhouette pixels, shaded differently by
renderers that test the view side of the shading normal).
"""

from __future__ import annotations

import math
import statistics
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import torch

from ..checks import InputError, check_shape
from ..prt import PrtSettings
from ..raster import Camera, default_camera
from ..raster.morphology import erode as erode_mask
from ..render.frame import TexturedAlbedo, render_mesh
from .cycles import CYCLES_TO_RELIGHTNET, render_blend
from .scene import export_scene
from .settings import CyclesSettings
from .world import world_light

__all__ = ["masked_rel_rmse", "comparison_mask", "front_facing", "ReferenceResult", "reference_comparison"]


def masked_rel_rmse(pred: torch.Tensor, ref: torch.Tensor, mask: torch.Tensor) -> float:
    """``‖pred − ref‖₂ / ‖ref‖₂`` over masked pixels.

    Args:
        pred, ref: (H, W, C) images. mask: (H, W) bool.
    """
    dims = check_shape(pred, ["H", "W", "C"], name="pred")
    check_shape(ref, ["H", "W", "C"], name="ref", dims=dims)
    check_shape(mask, ["H", "W"], name="mask", dims=dims)
    m = mask.bool()
    if not bool(m.any()):
        raise InputError("mask: no pixel to compare")
    d = (pred.double() - ref.double())[m]
    return float(d.pow(2).sum().sqrt() / ref.double()[m].pow(2).sum().sqrt().clamp_min(1e-30))


def comparison_mask(alpha_a: torch.Tensor, alpha_b: torch.Tensor, erode: int = 1) -> torch.Tensor:
    """(H, W) bool: pixels fully covered in both (H, W) coverage maps, eroded by ``erode`` pixels."""

    m = ((alpha_a > 0.999) & (alpha_b > 0.999)).float()
    return erode_mask(m[None, None], erode)[0, 0] > 0.5


def front_facing(normals: torch.Tensor, camera: Camera) -> torch.Tensor:
    """(H, W) bool: the (H, W, 3) world normal map faces the camera (n·v > 0, v toward the eye).

    The view ray of pixel (i, j) passes through its centre; ``camera`` is one perspective camera.
    """
    H, W = camera.size
    P = camera.proj[0].double()
    j = torch.arange(W, dtype=torch.float64) + 0.5
    i = torch.arange(H, dtype=torch.float64) + 0.5
    x = ((j * (2 / W) - 1) + P[0, 2]) / P[0, 0]
    y = ((1 - i * (2 / H)) + P[1, 2]) / P[1, 1]
    d_view = torch.stack([x[None].expand(H, W), y[:, None].expand(H, W), -torch.ones(H, W, dtype=torch.float64)], -1)
    d_world = d_view @ camera.R[0].double()  # Rᵀ d for row vectors
    return (normals.double() * -d_world).sum(-1) > 0


@dataclass(frozen=True, eq=False)
class ReferenceResult:
    """Images (H, W, 3 in Cycles' units), the comparison mask and per-bounce rows.

    ``rows``: one dict per bounce count with keys ``bounces``, ``vs_sh``, ``vs_sh_front``,
    ``vs_env``, ``vs_env_front``, ``ours_s``, ``cycles_sh_s``, ``cycles_env_s``.
    ``noise``: Cycles' own relative RMSE (two seeds, /√2) on the SH world at the last bounce count.
    """

    rows: list[dict]
    noise: float
    mask: torch.Tensor
    front: torch.Tensor
    ours: dict = field(default_factory=dict)
    ours_lifted: dict = field(default_factory=dict)
    cycles_sh: dict = field(default_factory=dict)
    cycles_env: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)


def _median_time(fn, repeat: int):
    times, out = [], None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times)


def _cycles(blend, spp, b, threads, seed, repeat):
    times, rgba = [], None
    for _ in range(max(1, repeat)):
        fr = next(iter(render_blend(blend, spp=spp, bounces=b, threads=threads, denoise=False, filter_width=0.01,
                                    seed=seed)))
        times.append(fr.seconds)
        rgba = fr.rgba
    return rgba, statistics.median(times)


def _posed_body(body, params: Mapping):
    """The one posed frame: (verts (V, 3), faces, normals, albedo for rendering, per-vertex albedo ρ
    for interreflection) — Anny's default outfit, else grey 0.6."""
    from ..body import AnnyBody, default_albedo

    with torch.no_grad():
        out = body(params)
    if out.batch_size != 1:
        raise InputError(f"params: expected one frame, got {out.batch_size}")
    v, f, n = out.verts[0], out.faces, out.normals[0]
    if isinstance(body, AnnyBody):
        a = default_albedo(body)
        return v, f, n, TexturedAlbedo(a.texture, body.uv, body.uv_faces), a.vertex
    grey = torch.full((v.shape[0], 3), 0.6)
    return v, f, n, grey, grey


def _world_lights(light: str, camera: Camera):
    """The environment map fixed to the world, and its band-limited SH version (lifted to be non-negative)."""
    wl_env = world_light(light, camera, "world", band_limit=False)
    if wl_env.kind != "envmap":
        raise InputError(f"light {light}: expected an environment map (a preset or an .exr/.hdr file)")
    return wl_env, world_light(light, camera, "world", band_limit=True, size=128, negative="lift")


def reference_comparison(
    body,
    params: Mapping,
    light: str = "city",
    bounces: Sequence[int] = (0, 1, 2),
    size: int = 128,
    cycles: CyclesSettings = CyclesSettings(),
    prt: PrtSettings = PrtSettings(),
    camera: Camera | None = None,
    repeat: int = 3,
    cycles_repeat: int = 1,
    erode: int = 0,
    workdir=None,
) -> ReferenceResult:
    """Compare relightnet's PRT render with Cycles for one posed frame (module docstring).

    Args:
        body: an Anny (or SMPL) body model. params: one frame's parameters.
        light: an environment map (preset name or ``.exr``/``.hdr``), fixed to the world.
        bounces: PRT interreflection bounces (and Cycles diffuse bounces) to compare.
        size: square image size. cycles: Cycles' samples per pixel and threads (None: all cores;
            its bounces are ``bounces``). prt: the PRT directions and their seed, which also seeds
            Cycles' noise (its bounces are ``bounces``). camera: default :func:`~relightnet.raster.default_camera`.
        repeat, cycles_repeat: timing repeats of relightnet (after one warm-up run) and of Cycles
            (after one 1-spp warm-up render); medians. erode: mask erosion in pixels.
        workdir: folder for the two .blend files (default: a temporary folder).

    Returns:
        :class:`ReferenceResult`.
    """
    from ..prt import vertex_transport

    spp, threads, seed = cycles.spp, cycles.threads, prt.seed
    camera = default_camera(size) if camera is None else camera
    bounces = [int(b) for b in bounces]
    if not bounces or min(bounces) < 0:
        raise InputError(f"bounces: expected integers >= 0, got {bounces}")
    (v, f, n, albedo, rho), (wl_env, wl_sh) = _posed_body(body, params), _world_lights(light, camera)
    L, L_lift = wl_env.sh, wl_sh.sh

    res = dict(ours={}, ours_lifted={}, cycles_sh={}, cycles_env={})
    rows = []
    front = None
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        blends = {}
        for name, wl in (("sh", wl_sh), ("env", wl_env)):
            blends[name] = Path(tmp) / f"{name}.blend"
            export_scene(blends[name], v[None], f, wl, camera, albedo=albedo, normals=n,
                         cycles=CyclesSettings(spp=spp, bounces=max(bounces)))
        next(iter(render_blend(blends["sh"], spp=1, bounces=0, threads=threads)))  # warm-up: kernel loading
        for b in bounces:
            def render_ours(b=b):
                T = vertex_transport(v, f, n, prt=replace(prt, bounces=b), albedo=rho if b else None)
                return T, render_mesh(v, f, T, albedo, L, camera, normals=n, light_frame="world", maps=True)

            if b == bounces[0]:
                render_ours()  # warm-up: ray-engine start-up
            (T, r), ours_s = _median_time(render_ours, repeat)
            r_lift = render_mesh(v, f, T, albedo, L_lift, camera, light_frame="world")
            ours = r.image[0] / CYCLES_TO_RELIGHTNET
            ours_lift = r_lift.image[0] / CYCLES_TO_RELIGHTNET
            cy_sh, sh_s = _cycles(blends["sh"], spp, b, threads, seed, cycles_repeat)
            cy_env, env_s = _cycles(blends["env"], spp, b, threads, seed, cycles_repeat)
            mask = comparison_mask(r.alpha[0], cy_sh[..., 3], erode)
            mask &= comparison_mask(r.alpha[0], cy_env[..., 3], erode)
            front = front_facing(r.normals[0], camera) & mask
            e = {}
            for key, a_img, ref in (("vs_sh", ours_lift, cy_sh), ("vs_env", ours, cy_env)):
                e[key] = masked_rel_rmse(a_img, ref[..., :3], mask)
                e[key + "_front"] = masked_rel_rmse(a_img, ref[..., :3], front)
            rows.append(dict(bounces=b, **e, ours_s=ours_s, cycles_sh_s=sh_s, cycles_env_s=env_s))
            res["ours"][b], res["ours_lifted"][b] = ours, ours_lift
            res["cycles_sh"][b], res["cycles_env"][b] = cy_sh, cy_env
        cy2, _ = _cycles(blends["sh"], spp, bounces[-1], threads, seed + 1, 1)
        noise = masked_rel_rmse(cy2[..., :3], res["cycles_sh"][bounces[-1]][..., :3], mask) / math.sqrt(2)
    settings = dict(light=light, size=size, spp=spp, n_dirs=prt.n_dirs, lmax=2, erode=erode,
                    lift=[float(x) for x in (L_lift[0] - L[0]) / math.sqrt(4 * math.pi)],
                    pixels=int(mask.sum()), front_pixels=int(front.sum()))
    return ReferenceResult(rows, noise, mask, front, settings=settings, **res)
