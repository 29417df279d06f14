"""Capture on real footage with hand-made masks: the reprojection and the silhouettes.

A video of a real person (not in this repository) is captured exactly as ``relightnet capture``
does (the package's own segmentation; the hand-made masks are used only to score), the captured
avatar is re-rendered in the source's camera, fitted poses and per-frame lights over the frames
(``--reproject``), and compared with them:

- PSNR inside the hand-made masks (sRGB, 8-bit scale) of the reprojection against the source;
- silhouette IoU against the hand-made masks of the bare fitted body and of the captured mesh;
- the capture's ms per frame after the fit and the process's peak memory.

    python benchmarks/bench_capture_real.py ../shared/real-video/turning.mp4 ../shared/real-video/turning_masks.mkv
"""

from __future__ import annotations

import argparse
import math
import resource
import tempfile
from pathlib import Path

import numpy as np
import torch
from common import cpu_name, table


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("video")
    ap.add_argument("masks", help="hand-made masks: a mask video (a pixel > 127 is the person)")
    ap.add_argument("--texture-size", type=int, default=1024)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    from relightnet.capture.texture import TextureOptions
    from relightnet.fit import FitBody
    from relightnet.fit.preview import fit_silhouettes
    from relightnet.io import read_video
    from relightnet.pipeline.backends import make_predictor
    from relightnet.pipeline.capture_check import reproject
    from relightnet.pipeline.capture_job import CaptureOptions, capture_file

    fb = FitBody()
    with tempfile.TemporaryDirectory() as d:
        rep = capture_file(args.video, Path(d) / "p.avatar.npz", make_predictor("torch", None, "cpu"),
                           CaptureOptions(texture=TextureOptions(size=args.texture_size)), fb=fb)
        reproject(rep, args.video, fb, Path(d) / "r.mkv", Path(d) / "m.mkv")
        sq = n = 0.0
        iou_cap, iou_bare = [], []
        res = rep.fit.result
        for t, (hand, cap, src, out) in enumerate(zip(read_video(args.masks), read_video(Path(d) / "m.mkv"),
                                                      read_video(args.video), read_video(Path(d) / "r.mkv"),
                                                      strict=False)):
            h, c = hand[..., 0] > 127, cap[..., 0] > 127
            b = fit_silhouettes(res, fb, start=t, stop=t + 1)[0].numpy() > 0.5
            iou_cap.append((h & c).sum() / max((h | c).sum(), 1))
            iou_bare.append((h & b).sum() / max((h | b).sum(), 1))
            diff = out[h].astype(np.float64) - src[h].astype(np.float64)
            sq, n = sq + float(np.square(diff).sum()), n + diff.size
    psnr = 10 * math.log10(255.0 ** 2 / (sq / n))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"{Path(args.video).name}: {len(iou_cap)} frames, CPU {cpu_name()}, {args.threads} threads, "
          f"texture {args.texture_size}²")
    print(table(["figure", "value"], [
        ["reprojection PSNR inside the hand-made masks (dB)", f"{psnr:.1f}"],
        ["silhouette IoU, bare fitted body", f"{np.mean(iou_bare):.3f}"],
        ["silhouette IoU, captured mesh (offsets)", f"{np.mean(iou_cap):.3f}"],
        ["surface seen (%)", f"{100 * rep.avatar.seen_share:.1f}"],
        ["capture ms per frame after the fit", f"{rep.ms_per_frame:.0f}"],
        ["peak memory (MiB)", f"{peak:.0f}"],
    ]))


if __name__ == "__main__":
    main()
