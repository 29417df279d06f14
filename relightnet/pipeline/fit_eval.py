"""How well :mod:`relightnet.fit` recovers a body, on generated clips whose true body is known.

``relightnet evaluate fit`` and ``benchmarks/bench_fit.py`` both run :func:`evaluate_fit_clip`:
the data generator's test clip (unseen body, motion, camera and light) goes through the shipped
segmentation (landmarks and masks) and the fit (warm-started windows, then the smoothing pass),
and the fit is compared with the generator's own body:

- ``mpjpe`` / ``pa_mpjpe``: mean per-landmark position error in mm over the 21 landmarks Anny's
  COCO regressor defines, hips aligned / after the best rotation, scale and translation per frame;
- ``lm2d``: median 2D landmark error, % of the true silhouette's height;
- ``iou_body``: silhouette IoU of the fitted body against the true body alone (its faces, no
  garments, rasterised in the clip's camera); ``iou_true`` against the true person mask
  (clothes and hair included, which a body cannot fill); ``iou_seg`` against the segmentation's;
  ``seg_iou_true``: the segmentation against the true mask;
- ``accel_raw`` / ``accel_smooth``: acceleration error before / after smoothing (mm/frame²);
- ``skate_fit`` / ``skate_retarget``: foot skating of the fitted motion placed on the ground, and
  after retargeting with the feet held (mm/frame);
- ``ms_fit``, ``cpu_ms_fit``, ``ms_seg``: wall / CPU ms per frame of the fit, wall ms of the segmentation.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import replace

import torch

from ..checks import InputError

__all__ = ["FIT_METRICS", "fit_eval_config", "evaluate_fit_clip", "evaluate_fit", "format_fit_report"]

#: The metrics of one clip, in report order (module docstring).
FIT_METRICS = ("mpjpe", "pa_mpjpe", "lm2d", "iou_body", "iou_true", "iou_seg", "seg_iou_true", "accel_raw",
               "accel_smooth", "skate_fit", "skate_retarget", "ms_fit", "cpu_ms_fit", "ms_seg")


def fit_eval_config(n_clips: int, n_frames: int, res: int = 256, seed: int = 0):
    """The generator's recipe for the evaluation clips: test split (unseen bodies, held-out env maps),
    one constant light per clip, no sensor noise, whole bodies in frame."""
    from ..data import SynthConfig

    if n_clips < 1 or n_frames < 2 or res < 64 or res % 16:
        raise InputError(f"fit evaluation: need >= 1 clip of >= 2 frames at a size >= 64 that is a multiple of 16, "
                         f"got {n_clips} clips, {n_frames} frames, {res}")
    return SynthConfig(seed=seed, res=res, lmax=2, n_dirs=16, counts={"train": 0, "val": 0, "test": n_clips},
                       hdri_test=("night", "sunrise"), noise_std=0.0, partial_crop_prob=0.0,
                       sequence_frames=n_frames, clip_lights="constant")


def _points(fb, result) -> torch.Tensor:
    with torch.no_grad():
        rest = fb.rest(fb.body.phenotype_tensor(result.phenotype[None]))
        return fb.points(result.pose, result.trans, rest)[0]


def _as_result(result, motion, fb):
    """A world-placed motion as a FitResult (to reuse the landmark code)."""
    return replace(result, pose=motion.pose[:, fb.bone_index], trans=motion.trans)


def _body_masks(geo, intr, size) -> torch.Tensor:
    """(T, H, W) the true body's silhouettes (the body's faces only, no garments), view-space verts."""
    from ..raster import Camera, rasterize
    from ..raster.camera import perspective_projection

    T = geo.verts.shape[0]
    P = perspective_projection(*intr, size)
    cam = Camera(torch.eye(4)[None].expand(T, 4, 4), P.expand(T, 4, 4), size)
    return rasterize(cam.transform(geo.verts), geo.faces[:geo.n_body_faces], size).mask.float()


def evaluate_fit_clip(cfg, index: int, fb, models, options=None) -> dict:
    """Fit test clip ``index`` of ``cfg`` (:func:`fit_eval_config`) and measure it (module docstring).

    Args:
        cfg: a SynthConfig with ``sequence_frames`` T. index: the clip. fb: a :class:`~relightnet.fit.FitBody`.
        models: loaded :class:`~relightnet.segment.PersonModels`. options: :class:`~relightnet.fit.FitOptions`.

    Returns:
        ``{metric: float}`` for :data:`FIT_METRICS`, and ``motion``: the clip's motion name.
    """
    from ..data import generate_sequence
    from ..data.framing import camera_intrinsics
    from ..data.render_sample import clip_geometry
    from ..fit import FitOptions, fit_observations, observe_frames, retarget_motion
    from ..fit.camera import project_points
    from ..fit.metrics import acceleration_error, foot_skating, landmark_error, mask_iou, mpjpe, pa_mpjpe
    from ..fit.preview import fit_silhouettes
    from ..fit.smooth import place_in_world, smooth_motion

    o = options if options is not None else FitOptions()
    T = int(cfg.sequence_frames)
    sample = generate_sequence(cfg, "test", index, T, body=fb.body)
    geo = clip_geometry(cfg, "test", index, T, body=fb.body)
    frames = torch.from_numpy(sample.arrays["image_composite"]).permute(0, 3, 1, 2).float() / 255
    true_mask = torch.from_numpy(sample.arrays["mask"]).float().reshape(T, cfg.res, cfg.res)
    t0 = time.perf_counter()
    obs = observe_frames(iter(frames), models, name=f"clip {index}", window=o.window)
    t_seg = time.perf_counter() - t0
    intr = camera_intrinsics(geo.camera)
    c0 = time.process_time()
    raw = fit_observations(obs, intr, fb, o.iters, o.warm_iters, o.window, o.fit_shape, o.weights)
    cpu_fit = time.process_time() - c0
    smooth = smooth_motion(raw, o.smooth_sigma)
    lm = fb.landmarks
    coco = torch.zeros(33, dtype=torch.bool)
    coco[lm.coco_slot] = True
    true_pts = torch.zeros(T, 33, 3)
    true_pts[:, lm.coco_slot] = torch.einsum("ks,bsd->bkd", lm.coco_weights, geo.verts[:, lm.coco_vertices])
    p_raw, p_s = _points(fb, raw), _points(fb, smooth)
    ys = torch.nonzero(true_mask.sum((0, 2)) > 0).flatten()
    height = float(ys.max() - ys.min() + 1) if len(ys) else float(cfg.res)
    sil, seg = fit_silhouettes(smooth, fb), obs.masks.unpack()
    world = place_in_world(smooth, fb)
    moved = retarget_motion(world, fb)  # the avatar's motion: the same body, feet held on the ground
    return {
        "mpjpe": float(mpjpe(p_s, true_pts, coco).mean()), "pa_mpjpe": float(pa_mpjpe(p_s, true_pts, coco).mean()),
        "lm2d": float(landmark_error(project_points(p_s, intr), project_points(true_pts, intr), coco,
                                     torch.full((T,), height)).median()),
        "iou_body": float(mask_iou(sil, _body_masks(geo, intr, (cfg.res, cfg.res))).mean()),
        "iou_true": float(mask_iou(sil, true_mask).mean()), "iou_seg": float(mask_iou(sil, seg).mean()),
        "seg_iou_true": float(mask_iou(seg, true_mask).mean()),
        "accel_raw": float(acceleration_error(p_raw, true_pts, coco).mean()),
        "accel_smooth": float(acceleration_error(p_s, true_pts, coco).mean()),
        "skate_fit": foot_skating(_points(fb, _as_result(smooth, world, fb))),
        "skate_retarget": foot_skating(_points(fb, _as_result(smooth, moved, fb))),
        "ms_fit": 1000 * raw.seconds / T, "cpu_ms_fit": 1000 * cpu_fit / T, "ms_seg": 1000 * t_seg / T,
        "motion": sample.meta["pose"].get("name", "?"),
    }


def evaluate_fit(n_clips: int = 3, n_frames: int = 12, res: int = 256, options=None, threads: int = 1,
                 progress=None) -> dict:
    """:func:`evaluate_fit_clip` on the first ``n_clips`` test clips of :func:`fit_eval_config`.

    Args:
        progress: called with (index, that clip's row) after each clip, or None.

    Returns:
        ``{"clips": [row, ...], "median": {metric: float}, "frames": T, "res": res}``.
    """
    from ..fit import FitBody
    from ..segment import PersonModels

    cfg = fit_eval_config(n_clips, n_frames, res)
    fb, models = FitBody(), PersonModels(threads=threads)
    rows = []
    for i in range(n_clips):
        rows.append(evaluate_fit_clip(cfg, i, fb, models, options))
        if progress is not None:
            progress(i, rows[-1])
    median = {k: float(statistics.median(r[k] for r in rows)) for k in FIT_METRICS}
    return {"clips": rows, "median": median, "frames": n_frames, "res": res}


def format_fit_report(result: dict) -> str:
    """The markdown table of :func:`evaluate_fit`'s result: a row per metric, a column per clip, the median."""
    rows = result["clips"]
    head = "| metric | " + " | ".join(f"clip {i} ({r['motion']})" for i, r in enumerate(rows)) + " | median |"
    lines = [head, "|---|" + "---|" * (len(rows) + 1)]
    for k in FIT_METRICS:
        lines.append(f"| {k} | " + " | ".join(f"{r[k]:.3g}" for r in rows) + f" | {result['median'][k]:.3g} |")
    return "\n".join(lines)
