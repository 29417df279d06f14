"""Fit quality and speed on generated clips, where the true body is known.

For each test clip (the data generator's clips: unseen bodies, motions, cameras and lights)
the frames go through the shipped segmentation (landmarks and masks), then ``relightnet.fit``
(warm-started windows, then the smoothing pass); the fit is compared with the true mesh:
MPJPE and PA-MPJPE (mm, over the 21 landmarks Anny's COCO regressor defines, hips aligned),
2D landmark error (median, % of the true silhouette's height), silhouette IoU against the
true body (the generator's body mesh alone, rasterised in the clip's camera), against the true
person mask (clothes and hair included, which a body cannot fill) and the segmentation's,
acceleration error before/after smoothing (mm/frame²), foot skating of the fitted motion placed
on the ground, and after retargeting with the feet
held (mm/frame), ms per frame of the fit (wall, and CPU time: the machine may be shared) and of
the segmentation.

    python benchmarks/bench_fit.py --clips 3 --frames 12 --res 256 --threads 2
    python benchmarks/bench_fit.py --speed --frames 40 --threads 2   # the fit's time alone, 720p
"""

from __future__ import annotations

import argparse
import statistics
import time

import torch

from relightnet.data import SynthConfig, clip_geometry, generate_sequence
from relightnet.data.framing import camera_intrinsics
from relightnet.fit import FitBody, fit_observations, observe_frames, project_points
from relightnet.fit.metrics import acceleration_error, foot_skating, landmark_error, mask_iou, mpjpe, pa_mpjpe
from relightnet.fit.preview import fit_silhouettes
from relightnet.fit.retarget import retarget_motion
from relightnet.fit.smooth import place_in_world, smooth_motion
from relightnet.segment import PersonModels


def _points(fb: FitBody, result) -> torch.Tensor:
    with torch.no_grad():
        rest = fb.rest(fb.body.phenotype_tensor(result.phenotype[None]))
        return fb.points(result.pose, result.trans, rest)[0]


def _clip(cfg, index, fb, models, args) -> dict:
    sample = generate_sequence(cfg, "test", index, args.frames, body=fb.body)
    geo = clip_geometry(cfg, "test", index, args.frames, body=fb.body)
    frames = torch.from_numpy(sample.arrays["image_composite"]).permute(0, 3, 1, 2).float() / 255
    true_mask = torch.from_numpy(sample.arrays["mask"]).float().reshape(args.frames, cfg.res, cfg.res)
    t0 = time.perf_counter()
    obs = observe_frames(iter(frames), models, name=f"clip {index}")
    t_seg = time.perf_counter() - t0
    intr = camera_intrinsics(geo.camera)
    c0 = time.process_time()
    raw = fit_observations(obs, intr, fb, args.iters, args.warm_iters, args.window)
    cpu_fit = time.process_time() - c0
    smooth = smooth_motion(raw, args.sigma)
    lm = fb.landmarks
    coco = torch.zeros(33, dtype=torch.bool)
    coco[lm.coco_slot] = True
    true_pts = torch.zeros(args.frames, 33, 3)
    true_pts[:, lm.coco_slot] = torch.einsum("ks,bsd->bkd", lm.coco_weights, geo.verts[:, lm.coco_vertices])
    p_raw, p_s = _points(fb, raw), _points(fb, smooth)
    ys = torch.nonzero(true_mask.sum((0, 2)) > 0).flatten()
    height = float(ys.max() - ys.min() + 1) if len(ys) else float(cfg.res)
    sil = fit_silhouettes(smooth, fb)
    world = place_in_world(smooth, fb)
    w_pts = _points(fb, _as_result(smooth, world, fb))
    moved = retarget_motion(world, fb)  # the avatar's motion: the same body, feet held on the ground
    r_pts = _points(fb, _as_result(smooth, moved, fb))
    return {
        "mpjpe": float(mpjpe(p_s, true_pts, coco).mean()), "pa_mpjpe": float(pa_mpjpe(p_s, true_pts, coco).mean()),
        "lm2d": float(landmark_error(project_points(p_s, intr), project_points(true_pts, intr), coco,
                                     torch.full((args.frames,), height)).median()),
        "iou_body": float(mask_iou(sil, _body_masks(geo, intr, (cfg.res, cfg.res))).mean()),
        "iou_true": float(mask_iou(sil, true_mask).mean()), "iou_seg": float(mask_iou(sil, obs.masks.unpack()).mean()),
        "seg_iou_true": float(mask_iou(obs.masks.unpack(), true_mask).mean()),
        "accel_raw": float(acceleration_error(p_raw, true_pts, coco).mean()),
        "accel_smooth": float(acceleration_error(p_s, true_pts, coco).mean()),
        "skate_fit": foot_skating(w_pts), "skate_retarget": foot_skating(r_pts),
        "ms_fit": 1000 * raw.seconds / args.frames, "cpu_ms_fit": 1000 * cpu_fit / args.frames,
        "ms_seg": 1000 * t_seg / args.frames,
        "motion": sample.meta["pose"].get("name", "?"),
    }


def _body_masks(geo, intr, size) -> torch.Tensor:
    """(T, H, W) the true body's silhouettes (the body's faces only, no garments), view-space verts."""
    from relightnet.raster import Camera, perspective_projection, rasterize

    T = geo.verts.shape[0]
    P = perspective_projection(*intr, size)
    cam = Camera(torch.eye(4)[None].expand(T, 4, 4), P.expand(T, 4, 4), size)
    return rasterize(cam.transform(geo.verts), geo.faces[:geo.n_body_faces], size).mask.float()


def _as_result(result, motion, fb):
    """The world-placed motion as a FitResult (to reuse the landmark code)."""
    from dataclasses import replace

    return replace(result, pose=motion.pose[:, fb.bone_index], trans=motion.trans)


def _timed(fb, obs, intr, args, iters, warm) -> tuple[float, float]:
    w0, c0 = time.perf_counter(), time.process_time()
    fit_observations(obs, intr, fb, iters, warm, args.window)
    return time.perf_counter() - w0, time.process_time() - c0


def _speed(fb, args) -> None:
    """Fit time alone (after the landmarks) at 720p on evidence made from a known walking body:
    wall and CPU seconds (CPU / threads estimates the wall time of an unloaded machine). The warm
    row is the video's steady state: (time of T frames − time of the first window) / (T − window)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from tests.fit.conftest import known_clip

    print("| input | frames | iterations | wall ms/frame | CPU ms/frame | CPU ms/frame / threads |\n"
          "|---|---|---|---|---|---|")
    obs, intr, _ = known_clip(fb, T=args.frames, size=(720, 1280), fov=60.0)
    _timed(fb, obs.slice(0, 1), intr, args, 5, 5)  # imports and first-call set-up, not timed
    rows = {}
    for kind, T in (("photo", 1), ("first window", min(args.window, args.frames)), ("video", args.frames)):
        wall, cpu = _timed(fb, obs.slice(0, T), intr, args, args.iters, args.warm_iters)
        rows[kind] = (T, wall, cpu)
    T1, w1, c1 = rows["first window"]
    T, w, c = rows["video"]
    rows["video, warm windows only"] = (T - T1, w - w1, c - c1)
    for kind, (n, wall, cpu) in rows.items():
        print(f"| {kind} 720p | {n} | {args.iters} first window, {args.warm_iters} later | "
              f"{1000 * wall / n:.0f} | {1000 * cpu / n:.0f} | {1000 * cpu / n / args.threads:.0f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--clips", type=int, default=3)
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--iters", type=int, default=120)
    ap.add_argument("--warm-iters", type=int, default=50)
    ap.add_argument("--window", type=int, default=8)
    ap.add_argument("--sigma", type=float, default=1.5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--speed", action="store_true", help="only time the fit (synthetic 720p evidence)")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    if args.speed:
        _speed(FitBody(), args)
        return
    cfg = SynthConfig(seed=0, res=args.res, lmax=2, n_dirs=16, counts={"train": 0, "val": 0, "test": args.clips},
                      hdri_test=("night", "sunrise"), noise_std=0.0, partial_crop_prob=0.0,
                      sequence_frames=args.frames, clip_lights="constant")
    fb, models = FitBody(), PersonModels(threads=args.threads)
    rows = []
    for i in range(args.clips):
        r = _clip(cfg, i, fb, models, args)
        rows.append(r)
        print(f"clip {i} ({r['motion']}): " + ", ".join(f"{k} {v:.3g}" for k, v in r.items() if k != "motion"),
              flush=True)
    keys = [k for k in rows[0] if k != "motion"]
    print("\n| metric | " + " | ".join(f"clip {i}" for i in range(len(rows))) + " | median |")
    print("|---|" + "---|" * (len(rows) + 1))
    for k in keys:
        vals = [r[k] for r in rows]
        print(f"| {k} | " + " | ".join(f"{v:.3g}" for v in vals) + f" | {statistics.median(vals):.3g} |")


if __name__ == "__main__":
    main()
