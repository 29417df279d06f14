"""Peak memory of the clean plate (``pipeline.clean_plate``) at real video sizes.

Run: ``.venv/bin/python benchmarks/bench_clean_plate_memory.py [--cases 1280x720x90 1920x1080x48]``
(one child process per case, so each starts from the same high-water mark).

Each case streams synthetic frames (a random textured background, a 20 %-wide "person" box walking across
it, its mask) into ``clean_plate`` with the default 48 samples. The frames are made one at a time from one
background, so what the table gives is the plate's own memory: the growth of the process's peak RSS
(``ru_maxrss``) over the call, next to what the samples themselves take (S uint8 frames and S bool masks)
and the wall time.
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import time


def _frames(H: int, W: int, n: int):
    import numpy as np

    rng = np.random.default_rng(0)
    bg = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    w = W // 5
    for t in range(n):
        x0 = int(t * (W - w) / max(n - 1, 1))
        m = np.zeros((H, W), np.float32)
        m[H // 4:H - H // 8, x0:x0 + w] = 1.0
        f = bg.copy()
        f[m > 0.5] = 40
        yield f, m


def _case(H: int, W: int, n: int) -> None:
    """Child: print the peak-RSS growth (MB) and the wall time (s) of one clean plate."""
    import torch

    from relightnet.pipeline.clean_plate import clean_plate

    torch.set_num_threads(2)
    frames = _frames(H, W, n)
    first = next(frames)
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss

    def pairs():
        yield first
        yield from frames

    t0 = time.perf_counter()
    cp = clean_plate(pairs(), n)
    dt = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(f"{(peak - base) / 1e3:.0f} {dt:.2f} {cp.n_samples}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", nargs="+", default=["1280x720x90", "1920x1080x48"], help="WxHxFRAMES")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        W, H, n = map(int, args.child.split("x"))
        _case(H, W, n)
        return
    print("| frames | samples S | S frames + masks, MB | peak RSS growth, MB | ratio | wall s |")
    print("|---|---|---|---|---|---|")
    for case in args.cases:
        W, H, n = map(int, case.split("x"))
        out = subprocess.run([sys.executable, __file__, "--child", case], capture_output=True, text=True, check=True)
        grow, dt, s = out.stdout.split()
        data = int(s) * H * W * 4 / 1e6
        print(f"| {W}×{H} × {n} | {s} | {data:.0f} | {grow} | {float(grow) / data:.2f} | {dt} |")


if __name__ == "__main__":
    main()
