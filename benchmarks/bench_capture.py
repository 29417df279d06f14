"""Capture quality, speed and memory on generated people, where the true texture, body and light are known.

For each person (an unseen generated adult turning one full circle, filmed once under each of
two lights) ``relightnet capture`` fits Anny, estimates each frame's light with the shipped CNN,
solves the offsets and fuses a de-lit texture; the result is compared with the truth: albedo
relative RMSE over the seen surface (and the raw, not de-lit, colours' for comparison), the seen
share, the light invariance of the two captures, silhouette IoU of the bare and the offset fit
against the true masks, a relit re-render in a new pose and light (PSNR, SSIM; also of the bare
fit and of the raw texture), the capture's ms per frame after the fit and the peak RSS
(definitions: relightnet/pipeline/capture_eval.py).

    python benchmarks/bench_capture.py --clips 2 --frames 48 --res 256 --threads 2
"""

from __future__ import annotations

import argparse
import time

import torch
from common import cpu_name

from relightnet.pipeline.backends import make_predictor
from relightnet.pipeline.capture_eval import evaluate_capture, format_capture_report


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--clips", type=int, default=2)
    ap.add_argument("--frames", type=int, default=48)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--texture", type=int, default=512)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=None, help="also write capture_report.md and capture_metrics.json here")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    print(f"{cpu_name()}, {args.threads} threads; {args.clips} people, {args.frames} frames at {args.res}², "
          f"texture {args.texture}²", flush=True)

    def show(i, r):
        print(f"clip {i} (seed {r['seed']}): " + ", ".join(f"{k} {v:.3g}" for k, v in r.items() if k != "seed"),
              flush=True)

    t0 = time.perf_counter()
    result = evaluate_capture(make_predictor("torch", None, "cpu"), args.out, args.clips, args.frames, args.res,
                              args.texture, progress=show)
    print("\n" + format_capture_report(result))
    print(f"\n{time.perf_counter() - t0:.0f} s in all")


if __name__ == "__main__":
    main()
