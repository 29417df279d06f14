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
import time

import torch

from relightnet.fit import FitBody, FitOptions, fit_observations
from relightnet.pipeline.fit_eval import evaluate_fit, format_fit_report


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
    options = FitOptions(iters=args.iters, warm_iters=args.warm_iters, window=args.window, smooth_sigma=args.sigma)

    def show(i, r):
        print(f"clip {i} ({r['motion']}): " + ", ".join(f"{k} {v:.3g}" for k, v in r.items() if k != "motion"),
              flush=True)

    result = evaluate_fit(args.clips, args.frames, args.res, options, args.threads, progress=show)
    print("\n" + format_fit_report(result))

if __name__ == "__main__":
    main()
