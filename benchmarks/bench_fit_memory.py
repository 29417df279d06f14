"""What a video fit holds per frame: the steps after the optimiser at T frames, and a packed mask's worst case.

Run: ``.venv/bin/python benchmarks/bench_fit_memory.py [--frames 2000 10000]`` (one child process per
length, so each starts from the same high-water mark).

For each T: a random fitted track of T frames (the fitted bones' rotations and a translation) is
smoothed (``fit.smooth_motion``), placed in the world (``fit.place_in_world``) and saved as a motion
file; the table gives the growth of the process's peak RSS (``VmHWM``) over each step. Then the
packed mask of random bits (a mask that does not compress) in a 4000 × 3120 frame (12.5 MP), at the
frame's size and at the fit's working resolution, against ``fit.MAX_FRAME_BYTES``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys


def _hwm_kb() -> int:
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM"):
            return int(line.split()[1])
    return 0


def _steps(T: int) -> None:
    """Child: print the VmHWM growth (MB) of smoothing, placing and saving a T-frame fit."""
    import os
    import tempfile

    import torch

    from relightnet.body import save_anny_motion
    from relightnet.fit import FitBody, default_intrinsics, smooth_motion
    from relightnet.fit.body_model import FIT_BONES
    from relightnet.fit.smooth import place_in_world
    from relightnet.fit.solve import FitResult

    fb = FitBody()
    g = torch.Generator().manual_seed(0)
    res = FitResult(0.1 * torch.randn(T, len(FIT_BONES), 3, generator=g),
                    torch.tensor([0.1, -0.9, -4.0]) + 0.01 * torch.randn(T, 3, generator=g),
                    torch.tensor([0.5, 0.78, 0.5, 0.5, 0.37, 0.5]), default_intrinsics((3120, 4000)), (3120, 4000),
                    torch.zeros(T), torch.zeros(T, dtype=torch.bool), 0.0)
    base = _hwm_kb()
    sm = smooth_motion(res, 1.5)
    after_smooth = _hwm_kb()
    motion = place_in_world(sm, fb, 30.0)
    after_place = _hwm_kb()
    with tempfile.TemporaryDirectory() as d:
        save_anny_motion(os.path.join(d, "m.npz"), motion)
    print(f"{(after_smooth - base) / 1e3:.0f} {(after_place - base) / 1e3:.0f} {(_hwm_kb() - base) / 1e3:.0f}")


def _noise_mask() -> str:
    import numpy as np

    from relightnet.fit.masks import MAX_FRAME_BYTES, PackedMasks

    H, W = 3120, 4000
    rng = np.random.default_rng(0)
    full, work = PackedMasks((H, W)), PackedMasks((H, W), window=1)
    for y0, y1 in ((0, H), (1000, 2000)):
        m = np.zeros((H, W), bool)
        m[y0:y1] = rng.random((y1 - y0, W), dtype=np.float32) < 0.5
        full.append(m)
        work.append(m)
    f, w = ([len(it[1]) for it in p._items] for p in (full, work))
    return (f"| packed mask of random bits, bytes a frame, 12.5 MP (whole frame / a 1000-row band) | "
            f"{f[0]:,} / {f[1]:,} at the frame's size | {w[0]:,} / {w[1]:,} at the working resolution "
            f"(MAX_FRAME_BYTES {MAX_FRAME_BYTES:,}) |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, nargs="+", default=[2000, 10000])
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        _steps(args.child)
        return
    print("| frames | smooth (MB) | + place in world (MB) | + save (MB) |\n|---|---|---|---|")
    for T in args.frames:
        out = subprocess.run([sys.executable, __file__, "--child", str(T)], capture_output=True, text=True,
                             check=True).stdout.split()
        print(f"| {T:,} | {out[0]} | {out[1]} | {out[2]} |", flush=True)
    print()
    print(_noise_mask())


if __name__ == "__main__":
    main()
