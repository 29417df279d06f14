"""How well ``relightnet capture`` makes an avatar, on generated people whose truth is known.

``relightnet evaluate capture`` and ``benchmarks/bench_capture.py`` both run :func:`evaluate_capture`.
Each clip is an unseen generated person (:func:`relightnet.capture.truth.turning_person`, seeds of
their own) turning one full circle; it is filmed twice, under the two lights of
:func:`~relightnet.capture.truth.light_pair`, and each film goes through :func:`capture_file`
(the fit, the CNN's light, the offsets, the de-lit texture). Against the truth:

- ``albedo_rmse``: relative RMSE of the de-lit texture (light A) against the true texture over the
  seen surface texels, after one global scale (:func:`~relightnet.capture.metrics.albedo_error`);
  ``albedo_rmse_raw``: the same of the raw (not de-lit) fused colours;
- ``seen``: share of the surface the capture saw (:func:`~relightnet.capture.metrics.seen_share`);
- ``invariance``: :func:`~relightnet.capture.metrics.light_invariance` of the two captures (A, B) over the
  texels both saw: 0 for an albedo the light does not change, 1 for one that de-lights nothing;
- ``iou_bare`` / ``iou_offset``: silhouette IoU against the true masks of the fitted body without and
  with the captured offsets, each rendered in the fit's camera;
- ``psnr`` / ``ssim``: a new pose (T-pose, turned 45°, 135°, 225°, 315°: root rotations the
  source never had) under a new light (``sunset``), in the default camera: the true body with the
  true texture against the captured body (its own phenotype and offsets, the truth's pose) with the
  captured texture; ``_bare``: the bare fitted body with the captured texture; ``_raw``: the
  captured body with the raw texture (the captured texture where the raw one saw nothing). Over
  the union of both person masks, sRGB in [0, 1] after one least-squares gain per render (linear,
  over that union): like the texture metrics, blind to a global exposure; ``iou_relit``: the IoU of
  the captured body's re-rendered masks and the truth's (where they differ, the union's pixels compare
  the person with the black background, which dominates a low PSNR);
- ``ms_per_frame``: the capture's time a frame after the fit (light A); ``peak_rss_mb``: the
  process's peak resident memory so far.
"""

from __future__ import annotations

import math
import resource
import statistics
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError

__all__ = ["CAPTURE_METRICS", "CAPTURE_TARGETS", "evaluate_capture", "evaluate_capture_clip", "format_capture_report",
           "meets_targets", "write_capture_report"]

#: The metrics of one clip, in report order (module docstring).
CAPTURE_METRICS = ("albedo_rmse", "albedo_rmse_raw", "seen", "invariance", "iou_bare", "iou_offset", "psnr", "ssim",
                   "psnr_bare", "ssim_bare", "psnr_raw", "ssim_raw", "iou_relit", "ms_per_frame", "peak_rss_mb")

#: The targets: metric → (comparison, bound) of the mean over the clips; the IoU is also above the bare
#: fit's and the re-render 2 dB above the raw texture's (:func:`meets_targets`).
CAPTURE_TARGETS = {"albedo_rmse": ("<=", 0.12), "seen": (">=", 0.85), "invariance": ("<=", 0.35),
                   "iou_offset": (">=", 0.92), "psnr": (">=", 26.0)}

#: The seed of the first clip (clip i: BASE_SEED + i); the tests' clips use others.
BASE_SEED = 7301
#: The re-render's root turns (radians) and its light preset.
NEW_ANGLES = (0.25 * math.pi, 0.75 * math.pi, 1.25 * math.pi, 1.75 * math.pi)
NEW_LIGHT = "sunset"
#: The truth clips' field of view (:func:`relightnet.raster.default_camera`'s, degrees): the fit is told it, as
#: ``evaluate fit`` gives the fit the clip's true camera (a video has no EXIF focal length, and the fit's
#: default of 60° would film a taller person nearer).
TRUTH_FOV_DEG = 35.0


def _true_masks(path) -> torch.Tensor:
    """(T, H, W) bool: a truth clip's mask video."""
    from ..io import read_video

    return torch.stack([torch.from_numpy(f[..., 0] > 127) for f in read_video(path)])


def _fit_ious(fit, fb, offsets: torch.Tensor, truth: torch.Tensor) -> tuple[float, float]:
    """Silhouette IoU of the fitted body without / with ``offsets`` (V,) against ``truth`` (T, H, W)."""
    from ..capture.metrics import silhouette_iou
    from ..capture.offsets import apply_offsets
    from ..fit.preview import chunk_frames, fit_camera, fit_meshes
    from ..raster import rasterize

    r = fit.result
    T, step = r.pose.shape[0], chunk_frames(r.size)
    bare, grown = [], []
    for a in range(0, T, step):
        out = fit_meshes(r, fb, a, min(a + step, T))
        cam = fit_camera(r, out.verts.shape[0])
        bare.append(rasterize(cam.transform(out.verts), out.faces, r.size).mask)
        grown.append(rasterize(cam.transform(apply_offsets(out.verts, out.normals, offsets)), out.faces, r.size).mask)
    return silhouette_iou(torch.cat(bare), truth), silhouette_iou(torch.cat(grown), truth)


def _new_params(body, phenotype) -> dict:
    """The re-render's pose: the T-pose turned by :data:`NEW_ANGLES`, feet at the origin."""
    from ..capture.truth import turning_params

    p = turning_params(body, len(NEW_ANGLES), pose="tpose")
    angle = torch.tensor(NEW_ANGLES, dtype=p["pose"].dtype)
    p["pose"][:, body.joint_index("root")] = angle[:, None] * torch.tensor([0.0, 1.0, 0.0], dtype=angle.dtype)
    return {**p, "phenotype": phenotype}


def _render(body_like, params, light, texture, size) -> tuple[torch.Tensor, torch.Tensor]:
    """(N, H, W, 3) linear premultiplied images and (N, H, W) bool masks of the re-render."""
    from ..prt import PrtSettings
    from ..raster import default_camera
    from ..render.frame import TexturedAlbedo
    from ..render.jobs import render_body_frames

    albedo = TexturedAlbedo(texture, body_like.uv, body_like.uv_faces)
    frames = list(render_body_frames(body_like, params, light, albedo, camera=default_camera(size),
                                     n_frames=len(NEW_ANGLES), prt=PrtSettings(n_dirs=64), visible_only=True))
    return (torch.stack([f.render.image[0] for f in frames]).float(),
            torch.stack([f.render.alpha[0] > 0.5 for f in frames]))


def _agreement(img, mask, ref, ref_mask) -> tuple[float, float]:
    """PSNR and SSIM of a render against the truth's over the union of their masks (module docstring)."""
    from ..capture.metrics import person_psnr, person_ssim
    from ..color import linear_to_srgb

    union = mask | ref_mask
    m = union[..., None].to(img.dtype)
    gain = float((img * ref * m).sum() / (img * img * m).sum().clamp_min(1e-12))
    a, b = (linear_to_srgb(x.clamp(0, 1)) for x in (gain * img, ref))
    return person_psnr(a, b, union), person_ssim(a, b, union)


def _relit(fb, clip, avatar, raw_tex, seen) -> dict:
    """The re-render's figures (module docstring): ``psnr``, ``ssim`` and their ``_bare`` and ``_raw``."""
    from ..capture import CapturedBody
    from ..capture.metrics import silhouette_iou
    from ..light import load_light

    light = load_light(NEW_LIGHT)
    params = _new_params(fb.body, clip.params["phenotype"])
    ref, ref_m = _render(fb.body, params, light, clip.texture, clip.size)
    raw = torch.where(seen[..., None], raw_tex.float(), avatar.texture)
    bodies = {"": (CapturedBody(fb.body, avatar), avatar.texture),
              "_bare": (CapturedBody(fb.body, replace(avatar, offsets=torch.zeros_like(avatar.offsets))),
                        avatar.texture),
              "_raw": (CapturedBody(fb.body, avatar), raw)}
    row = {}
    for suffix, (body_like, tex) in bodies.items():
        img, mask = _render(body_like, params, light, tex, clip.size)
        row["psnr" + suffix], row["ssim" + suffix] = _agreement(img, mask, ref, ref_m)
        if not suffix:
            row["iou_relit"] = silhouette_iou(mask, ref_m)
    return row


def evaluate_capture_clip(predictor, work, seed: int, frames: int = 48, res: int = 256, texture_size: int = 512,
                          options=None, fb=None) -> dict:
    """Film one generated person under both lights, capture both films and measure them (module docstring).

    Args:
        predictor: the CNN's predictor (:func:`relightnet.pipeline.backends.make_predictor`).
        work: a scratch folder (the clips and avatar files). seed: the person.
        frames: T per film. res: frame side. texture_size: S of the true and the captured textures.
        options: :class:`~relightnet.pipeline.capture_job.CaptureOptions` (its texture size is replaced by
            ``texture_size``, its fit's field of view by :data:`TRUTH_FOV_DEG`).
        fb: a :class:`~relightnet.fit.FitBody` (made when None).

    Returns:
        ``{metric: float}`` for :data:`CAPTURE_METRICS`, and ``seed``.
    """
    from ..capture.metrics import albedo_error, light_invariance, surface_texels
    from ..capture.texture import TextureOptions
    from ..capture.truth import light_pair, turning_person
    from ..data.textures import uv_atlas
    from ..fit import FitBody
    from .capture_job import CaptureOptions, capture_file

    fb = FitBody() if fb is None else fb
    o = options if options is not None else CaptureOptions()
    o = replace(o, texture=replace(o.texture if o.texture is not None else TextureOptions(), size=int(texture_size)),
                fit=replace(o.fit, fov_deg=TRUTH_FOV_DEG))
    work = Path(work)
    clips, reports = [], []
    for name, light in zip("ab", light_pair(), strict=True):
        clips.append(turning_person(work / f"{seed}_{name}", fb.body, light, frames, (res, res), seed,
                                    texture_size=texture_size))
        reports.append(capture_file(clips[-1].video, work / f"{seed}_{name}.avatar.npz", predictor, o, raw=True))
    ca, (ra, rb) = clips[0], reports
    surface = surface_texels(uv_atlas(fb.body, texture_size))
    iou_bare, iou_offset = _fit_ious(ra.fit, fb, ra.avatar.offsets, _true_masks(ca.masks))
    return {
        "albedo_rmse": albedo_error(ra.avatar.texture, ca.texture, ra.seen & surface),
        "albedo_rmse_raw": albedo_error(ra.raw_texture, ca.texture, ra.seen & surface),
        "seen": ra.avatar.seen_share,
        "invariance": light_invariance(ra.avatar.texture, rb.avatar.texture, ra.raw_texture, rb.raw_texture,
                                       ra.seen & rb.seen & surface),
        "iou_bare": iou_bare, "iou_offset": iou_offset,
        **_relit(fb, ca, ra.avatar, ra.raw_texture, ra.seen),
        "ms_per_frame": float(ra.ms_per_frame),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "seed": int(seed),
    }


def evaluate_capture(predictor, out_dir=None, clips: int = 2, frames: int = 48, res: int = 256,
                     texture_size: int = 512, seed: int = BASE_SEED, options=None, progress=None) -> dict:
    """:func:`evaluate_capture_clip` on ``clips`` people (seeds ``seed``, ``seed + 1``, …).

    Args:
        predictor: the CNN's predictor. out_dir: where ``capture_report.md`` and ``capture_metrics.json``
            are written (atomically; the folder is made only once every clip is measured); None: nowhere.
        clips, frames, res, texture_size: the clips (≥ 1 clip of ≥ 8 frames at a side ≥ 64, a multiple of 16;
            a texture side ≥ 64). options: :class:`~relightnet.pipeline.capture_job.CaptureOptions`.
        progress: called with (index, that clip's row) after each clip, or None.

    Returns:
        ``{"clips": [row, ...], "mean": {metric: float}, "frames", "res", "texture_size"}``.
    """
    from ..fit import FitBody

    if clips < 1 or frames < 8 or res < 64 or res % 16 or texture_size < 64:
        raise InputError(f"capture evaluation: need >= 1 clip of >= 8 frames at a size >= 64 that is a multiple of "
                         f"16 and a texture of >= 64, got {clips} clips, {frames} frames, {res}, {texture_size}")
    fb, rows = FitBody(), []
    with tempfile.TemporaryDirectory(prefix="capture_eval_") as work:
        for i in range(clips):
            rows.append(evaluate_capture_clip(predictor, work, seed + i, frames, res, texture_size, options, fb))
            if progress is not None:
                progress(i, rows[-1])
    mean = {k: float(statistics.fmean(r[k] for r in rows)) for k in CAPTURE_METRICS}
    result = {"clips": rows, "mean": mean, "frames": frames, "res": res, "texture_size": texture_size}
    result["targets_met"] = meets_targets(mean)
    if out_dir is not None:
        write_capture_report(result, out_dir)
    return result


def meets_targets(mean: dict) -> dict:
    """Each target of :data:`CAPTURE_TARGETS` (and ``iou_over_bare``, ``psnr_over_raw``: the offsets' IoU
    above the bare fit's, the re-render ≥ 2 dB above the raw texture's) → whether ``mean`` meets it."""
    ok = {k: (mean[k] <= b if op == "<=" else mean[k] >= b) for k, (op, b) in CAPTURE_TARGETS.items()}
    ok["iou_over_bare"] = mean["iou_offset"] > mean["iou_bare"]
    ok["psnr_over_raw"] = mean["psnr"] >= mean["psnr_raw"] + 2.0
    return ok


def _target(k: str) -> str:
    if k in CAPTURE_TARGETS:
        op, b = CAPTURE_TARGETS[k]
        return ("≤ " if op == "<=" else "≥ ") + (f"{100 * b:.0f}%" if k == "seen" else f"{b:g}") + \
            (" and > iou_bare" if k == "iou_offset" else " and ≥ psnr_raw + 2" if k == "psnr" else "")
    return ""


def format_capture_report(result: dict) -> str:
    """The markdown table of :func:`evaluate_capture`'s result: a row per metric, a column per clip, the mean,
    the target and whether the mean meets it."""
    rows, ok = result["clips"], result["targets_met"]
    head = "| metric | " + " | ".join(f"clip {i} (seed {r['seed']})" for i, r in enumerate(rows)) + \
        " | mean | target | met |"
    lines = [head, "|---|" + "---|" * (len(rows) + 3)]
    met = {"iou_offset": ok["iou_offset"] and ok["iou_over_bare"], "psnr": ok["psnr"] and ok["psnr_over_raw"]}
    for k in CAPTURE_METRICS:
        t = _target(k)
        flag = ("yes" if met.get(k, ok.get(k)) else "no") if t else ""
        lines.append(f"| {k} | " + " | ".join(f"{r[k]:.3g}" for r in rows) + f" | {result['mean'][k]:.3g} | {t} | "
                     f"{flag} |")
    return "\n".join(lines)


def write_capture_report(result: dict, out_dir) -> tuple[Path, Path]:
    """``capture_report.md`` and ``capture_metrics.json`` of :func:`evaluate_capture`'s result, atomically."""
    import json

    from ..io import atomic_write

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    md, js = out / "capture_report.md", out / "capture_metrics.json"
    with atomic_write(md, "w") as f:
        f.write(f"# Capturing people: {len(result['clips'])} generated people turning, {result['frames']} frames "
                f"at {result['res']}², texture {result['texture_size']}²\n\n{format_capture_report(result)}\n\n"
                "Figures as defined in relightnet/pipeline/capture_eval.py; the targets are of the mean.\n")
    with atomic_write(js, "w") as f:
        json.dump(result, f, indent=2, default=lambda x: x.item() if isinstance(x, np.generic) else str(x))
    return md, js
