"""One clip of the 2D/3D comparison (:mod:`relightnet.pipeline.compare`): both paths under three
lights, and the clip's numbers.

:func:`compare_clip` runs the stages of one clip — *estimate* (the CNN's light per target frame),
*smooth* (over the clip, :func:`~relightnet.temporal.smooth_video_lights`), and the two
paths: the 2D path's predictions relit by :func:`~relightnet.pipeline.relight_bands.relight_over_photo`
(as ``relight-video`` relights; the relit person alone, in linear RGB), the 3D path's PRT render
shaded by :func:`relightnet.render.shade`;
:func:`clip_metrics` compares the six outputs with the ground truth.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
import torch

from ..checks import InputError, sh_order_from_count
from ..color import linear_to_srgb
from ..io.image import to_uint8
from ..prt import PrtSettings
from ..render.shading import composite, shade
from ..sh.io import resize_sh
from ..sh.light_solve import stack_evidence
from ..temporal import jitter, light_distance, light_error
from ..temporal.registry import smooth_video_lights
from ..temporal.switches import frame_colour
from . import metrics as M
from .backends import as_predictor
from .relight_bands import relight_over_photo

__all__ = ["PATHS", "LIGHTS", "CLIP_FPS", "CLIP_FIELDS", "ClipOutputs", "source_light", "compare_clip",
           "clip_metrics"]

#: The two paths and the three lights each is shaded with (the row order of the tables).
PATHS = ("2d", "3d")
LIGHTS = ("true", "raw", "smoothed")
#: Frame rate of the generated clips (``meta["fps"]``).
CLIP_FPS = 30.0
#: Arrays of a clip that the comparison reads.
CLIP_FIELDS = ("image", "image_composite", "mask", "albedo", "transport", "light", "background")


@dataclass(frozen=True, eq=False)
class ClipOutputs:
    """What :func:`compare_clip` makes for one clip (channels-last, linear RGB).

    Attributes:
        lights: ``"true"``, ``"raw"``, ``"smoothed"`` → (T, K, 3), K of the data.
        renders: ``(path, light)`` → (T, H, W, 3) output of a path under a light, 0 off its mask.
        alpha_3d: (T, H, W) coverage of the 3D path's rasterization.
        source: (T, H, W, 3) the 2D path's input image I_src (linear).
        outliers, switches: (T,) bool, what the smoother flagged (all False without smoothing).
        seconds: time spent per stage (``cnn``, ``prt``, ``render``).
    """

    lights: dict
    renders: dict
    alpha_3d: torch.Tensor
    source: torch.Tensor
    outliers: torch.Tensor
    switches: torch.Tensor
    seconds: dict = field(default_factory=dict)


def source_light(name: str = "studio", lmax: int = 2, level: float = 1.0) -> torch.Tensor:
    """The 2D path's fixed source light: a preset scaled so that its level is ``level``.

    The level is the data generator's exposure rule (:mod:`relightnet.data.lights`: the
    largest luminance of the irradiance over all normals), so I_src is exposed like the data.

    Returns:
        (K, 3) float32, K = (lmax+1)².
    """
    from ..data.lights import light_level
    from ..light import preset_light

    sh = preset_light(name, lmax)
    return (sh * (level / light_level(sh))).float()


def _clip_inputs(clip: dict, source: str, lmax: int):
    """The clip's arrays as tensors: mask (T, H, W), the target frames (T, 3, H, W) uint8, and the
    2D path's input I_src = albedo ⊙ (transport · L_src) (T, H, W, 3) linear (module docstring)."""
    T = np.asarray(clip["light"]).shape[0]
    mask = torch.from_numpy(np.asarray(clip["mask"], np.float32))
    comp = torch.from_numpy(np.asarray(clip["image_composite"])).permute(0, 3, 1, 2)
    albedo = torch.from_numpy(np.asarray(clip["albedo"], np.float32))
    transport = torch.from_numpy(np.asarray(clip["transport"], np.float32))
    src = shade(albedo, transport, source_light(source, lmax)[None].expand(T, -1, -1))
    return mask, comp, src


def _relight_2d(crops: list, photos: torch.Tensor, light: torch.Tensor, cnn_albedo: bool) -> torch.Tensor:
    """The 2D path under (T, K, 3) lights, each frame's prediction (:class:`~relightnet.model.inference.CropMaps`)
    relit with its light: (T, H, W, 3) linear, 0 off the person."""
    return torch.stack([relight_over_photo(c, p, L, detail=not cnn_albedo, keep_exposure=False, composite=False).image
                        for c, p, L in zip(crops, photos, light, strict=True)])


def _cpu_float(crop):
    """A frame's :class:`~relightnet.model.inference.CropMaps` in float32 on the CPU (where the clip's arrays are)."""
    def cpu(x):
        return None if x is None else x.float().cpu()

    return dataclasses.replace(crop, albedo=cpu(crop.albedo), transport=cpu(crop.transport), light=cpu(crop.light),
                               mask=cpu(crop.mask))


def _render_3d(maps: dict, light: torch.Tensor) -> torch.Tensor:
    """The 3D path under (T, K, 3) lights: A ⊙ (T · L) over black where the mesh is not (T, H, W, 3)."""
    fg = shade(maps["albedo"], maps["transport"], light)
    return composite(fg, maps["alpha"], torch.zeros_like(fg))


def _clip_transport(geometry, t: int, lmax: int, prt) -> torch.Tensor:
    """Frame ``t``'s PRT (V, K) in the camera's light frame, cast in the frame the generator casts it in
    (the person's world frame, before the view's yaw: the same directions there), its garments'
    midpoints ray cast only at shadow edges as there (:func:`relightnet.prt.refined_transport`), and
    turned into the camera's (:func:`relightnet.data.person.transport_to_camera`)."""
    from ..data.person import transport_to_camera
    from ..prt import refined_transport

    w2c = geometry.world_to_camera.double()
    R, tr = w2c[:3, :3], w2c[:3, 3]
    v_world = ((geometry.verts[t].double() - tr) @ R).float()  # v_cam = R v_world + tr
    n_world = (geometry.normals[t].double() @ R).float()
    if prt.threads is None:
        prt = replace(prt, threads=torch.get_num_threads())
    Tw = refined_transport(v_world, geometry.faces, n_world, geometry.midpoints, lmax=lmax, prt=prt, manifold="ignore")
    return transport_to_camera(Tw, R, lmax)


def compare_clip(model, clip: dict, geometry, prt: PrtSettings = PrtSettings(n_dirs=64), smoothing: str = "auto",
                 source: str = "studio", tick=None, cnn_albedo: bool = False) -> ClipOutputs:
    """Run both paths on one clip (module docstring of :mod:`relightnet.pipeline.compare`).

    Args:
        model: the CNN: a :class:`~relightnet.model.RelightNet` (eval mode, any device; run at its
            training size) or a predictor of :mod:`relightnet.pipeline.backends` (torch or ONNX).
        clip: the clip's arrays as stored (numpy, leading T): :data:`CLIP_FIELDS`.
        geometry: its :class:`~relightnet.data.render_sample.ClipGeometry` (T frames).
        prt: the 3D path's PRT (:class:`~relightnet.prt.PrtSettings`: directions, their rotation seed,
            interreflections; a bounce reflects off 0.5-grey surfaces, ``vertex_transport``'s default;
            threads: the torch threads when None).
        smoothing: a name of :data:`~relightnet.names.VIDEO_SMOOTHING`.
        source: preset name of the 2D path's source light.
        tick: optional callable, called after every frame.
        cnn_albedo: the 2D path relights the CNN's albedo, not the photo's (module docstring).

    Returns:
        :class:`ClipOutputs`.
    """
    from ..render.frame import render_mesh

    true = torch.from_numpy(np.asarray(clip["light"], np.float32))
    T, K = true.shape[0], true.shape[1]
    lmax = sh_order_from_count(K)
    predict = as_predictor(model)
    mask, comp, src = _clip_inputs(clip, source, lmax)
    if geometry.verts.shape[0] != T:
        raise InputError(f"geometry: {geometry.verts.shape[0]} frames for a clip of {T}")
    secs = {"cnn": 0.0, "prt": 0.0, "render": 0.0}
    raw, evs, priors, preds, photos, maps = [], [], [], [], [], {"albedo": [], "transport": [], "alpha": []}
    for t in range(T):
        c0 = time.perf_counter()
        light, ev, prior = predict.light_evidence(comp[t], mask[t])  # estimate (from the target frame)
        raw.append(resize_sh(light.float().cpu(), lmax))
        evs.append(ev)
        priors.append(prior)
        photos.append(to_uint8(src[t]).permute(2, 0, 1))  # the 2D path's input photo
        preds.append(_cpu_float(predict.crop(photos[-1], mask[t])))
        c1 = time.perf_counter()
        Tv = _clip_transport(geometry, t, lmax, prt)
        c2 = time.perf_counter()
        rend = render_mesh(geometry.verts[t], geometry.faces, Tv, geometry.albedo, true[t], geometry.camera,
                           maps=True)
        for name, value in (("albedo", rend.albedo), ("transport", rend.transport), ("alpha", rend.alpha)):
            maps[name].append(value[0])
        c3 = time.perf_counter()
        secs["cnn"] += c1 - c0
        secs["prt"] += c2 - c1
        secs["render"] += c3 - c2
        if tick is not None:
            tick()
    raw = torch.stack(raw)
    colour = torch.stack([frame_colour(comp[t]) for t in range(T)])  # the switches seen in the frames
    smoothed, outliers, switches, _ = smooth_video_lights(raw, smoothing, *stack_evidence(evs, priors),
                                                       predict.solve_reg, CLIP_FPS, colour=colour)
    lights = {"true": true, "raw": raw, "smoothed": resize_sh(smoothed, lmax)}
    photos = torch.stack(photos)
    maps = {k: torch.stack(v) for k, v in maps.items()}
    renders = {}
    for name, L in lights.items():
        renders[("2d", name)] = _relight_2d(preds, photos, resize_sh(L, predict.lmax), cnn_albedo)
        renders[("3d", name)] = _render_3d(maps, L)
    return ClipOutputs(lights, renders, maps["alpha"], src, outliers, switches, secs)


def _srgb(x: torch.Tensor) -> torch.Tensor:
    """(T, H, W, 3) linear → (T, 3, H, W) sRGB-encoded in [0, 1]."""
    return linear_to_srgb(x.clamp(0, 1)).permute(0, 3, 1, 2)


def _floats(x: torch.Tensor) -> list:
    return [float(v) for v in x.flatten()]


def clip_metrics(out: ClipOutputs, gt: torch.Tensor, mask: torch.Tensor) -> dict:
    """The numbers of one clip.

    Args:
        out: a clip's :class:`ClipOutputs`.
        gt: (T, H, W, 3) the true relit frames (linear).
        mask: (T, H, W) the ground-truth mask.

    Returns:
        ``{"rows": [{"path", "light", "rmse", "psnr", "ssim", "temporal", "per_frame": {...}}, ...] (6),
        "light": {"raw"|"smoothed": {"error", "relative", "jitter", "per_frame"}, "true": {"jitter"}},
        "mask_iou_3d", "smoother_outliers", "smoother_switches"}``; per-frame lists have T entries
        (``temporal``: T − 1, empty for a single frame); jitter is NaN below 3 frames.
    """
    g = _srgb(gt)
    rows = []
    for path in PATHS:
        for light in LIGHTS:
            x = _srgb(out.renders[(path, light)])
            per = {"rmse": M.masked_rmse(x, g, mask), "psnr": M.psnr(x, g, mask), "ssim": M.ssim(x, g, mask)}
            te = M.temporal_error(x, g, mask, reduction="none") if len(g) > 1 else torch.zeros(0)
            row = {"path": path, "light": light, **{k: float(v.mean()) for k, v in per.items()},
                   "temporal": float(M.temporal_error(x, g, mask)) if len(g) > 1 else math.nan,
                   "per_frame": {**{k: _floats(v) for k, v in per.items()}, "temporal": _floats(te)}}
            rows.append(row)
    true = out.lights["true"].double()
    lights = {}
    for name in ("raw", "smoothed"):
        est = out.lights[name].double()
        lights[name] = {"error": float(light_error(est, true)), "relative": float(light_error(est, true, True)),
                        "per_frame": _floats(light_distance(est, true))}
    for name in ("raw", "smoothed", "true"):
        lights.setdefault(name, {})["jitter"] = float(jitter(out.lights[name].double())) if len(g) >= 3 else math.nan
    gm, am = mask > 0.5, out.alpha_3d > 0.5
    return {"rows": rows, "light": lights, "mask_iou_3d": float((gm & am).sum() / (gm | am).sum().clamp_min(1)),
            "smoother_outliers": torch.nonzero(out.outliers).flatten().tolist(),
            "smoother_switches": torch.nonzero(out.switches).flatten().tolist()}
