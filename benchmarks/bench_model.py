"""CNN speed: training samples/s and inference ms/frame at 256² and 512², GFLOPs and GFLOP/s.

Run: ``.venv/bin/python benchmarks/bench_model.py [--checkpoint relightnet/weights/relightnet_small.pt]``
(2 threads; torch eager, channels_last vs contiguous). The machine's fp32 matmul peak is
measured in the same run (a 2048² GEMM) so achieved GFLOP/s is quoted against it.
"""

from __future__ import annotations

import argparse
import os
import sys

import torch
from torch.utils.flop_counter import FlopCounterMode

sys.path.insert(0, os.path.dirname(__file__))
from common import median_ms, table  # noqa: E402

from relightnet.model import NetConfig, RelightNet, normalize_input, relight_losses  # noqa: E402
from relightnet.model.checkpoint import load_model  # noqa: E402


def gemm_peak() -> float:
    a, b = torch.randn(2048, 2048), torch.randn(2048, 2048)
    return 2 * 2048**3 / (median_ms(lambda: a @ b, repeat=5) * 1e-3) / 1e9


def flops(model, x) -> float:
    with FlopCounterMode(display=False) as fc, torch.no_grad():
        model(x)
    return fc.get_total_flops() / 1e9


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--checkpoint", default=None, help="model to time (default: the shipped one)")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    try:
        model = load_model(args.checkpoint)
    except Exception:  # no shipped model yet: time the architecture of train/configs/small.yaml
        model = RelightNet(NetConfig(width=16, max_width=128, light_hidden=128)).eval()
    peak = gemm_peak()
    params = sum(p.numel() for p in model.parameters()) / 1e6
    rows = []
    for size in (256, 512):
        x = normalize_input(torch.rand(1, 3, size, size), torch.ones(1, 1, size, size))
        gf = flops(model, x)
        for fmt in ("contiguous", "channels_last"):
            m = model.to(memory_format=torch.channels_last if fmt == "channels_last" else torch.contiguous_format)
            xi = x.contiguous(memory_format=torch.channels_last) if fmt == "channels_last" else x
            with torch.no_grad():
                ms = median_ms(lambda m=m, xi=xi: m(xi), repeat=5)
            rows.append([f"inference {size}²", fmt, ms, gf, gf / (ms * 1e-3), gf / (ms * 1e-3) / peak])
    model = model.to(memory_format=torch.contiguous_format).train()
    opt = torch.optim.AdamW(model.parameters(), lr=1e-4)
    k = model.config.n_coeffs
    for size, bs in ((128, 8), (256, 4)):
        batch = {"image": torch.rand(bs, 3, size, size), "mask": torch.ones(bs, 1, size, size),
                 "albedo": torch.rand(bs, 3, size, size), "transport": torch.randn(bs, k, size, size),
                 "light": torch.randn(bs, k, 3)}
        x = normalize_input(batch["image"], batch["mask"])

        def step(batch=batch, x=x):
            opt.zero_grad()
            relight_losses(model(x), batch)["total"].backward()
            opt.step()

        ms = median_ms(step, repeat=3)
        gf = 3 * flops(model, x)  # forward + backward ≈ 3× forward
        rows.append([f"training {size}², batch {bs}", f"{bs / (ms * 1e-3):.1f} samples/s", ms, gf,
                     gf / (ms * 1e-3), gf / (ms * 1e-3) / peak])
    print(f"threads {args.threads}; params {params:.2f} M; fp32 GEMM peak measured {peak:.0f} GFLOP/s\n")
    print(table(["job", "layout / rate", "median ms", "GFLOP", "GFLOP/s", "of peak"], rows))


if __name__ == "__main__":
    main()
