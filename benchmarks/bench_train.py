"""Training speed on the CPU: fp32 vs bf16 autocast, contiguous vs channels-last, per light mode.

Run: ``.venv/bin/python benchmarks/bench_train.py [--threads 2] [--size 128] [--batch 8]``

One training step (forward, KE18 losses, backward, AdamW) on a random batch, median of a few
steps, for each network width and light mode (``head``: KE18's regression; ``solve`` and
``hybrid``: the light solved from the maps). bf16 needs AVX512-BF16 or AMX to be fast: the
CPU's flags are printed with the table. Ratios are against fp32 contiguous in the same run.
"""

from __future__ import annotations

import argparse
import os
import sys

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import median_ms, table  # noqa: E402

from relightnet.model import LossWeights, NetConfig, RelightNet, normalize_input, relight_losses  # noqa: E402


def cpu_flags() -> str:
    try:
        text = open("/proc/cpuinfo").read()
    except OSError:
        return "unknown CPU"
    name = next((ln.split(":", 1)[1].strip() for ln in text.splitlines() if ln.startswith("model name")), "?")
    flags = next((ln.split(":", 1)[1].split() for ln in text.splitlines() if ln.startswith("flags")), [])
    keep = [f for f in ("avx512_bf16", "amx_bf16", "avx512_vnni", "avx_vnni") if f in flags]
    return f"{name} ({', '.join(keep) or 'no bf16/vnni flags'})"


def step_ms(net_cfg: NetConfig, size: int, bs: int, precision: str, layout: str) -> float:
    torch.manual_seed(0)
    model = RelightNet(net_cfg).train()
    if layout == "channels_last":
        model = model.to(memory_format=torch.channels_last)
    opt = torch.optim.AdamW(model.parameters(), lr=1e-4)
    k = net_cfg.n_coeffs
    mask = torch.ones(bs, 1, size, size)
    mask[..., : size // 8, :] = 0
    batch = {"image": torch.rand(bs, 3, size, size), "mask": mask, "albedo": torch.rand(bs, 3, size, size),
             "transport": torch.randn(bs, k, size, size), "light": torch.randn(bs, k, 3)}
    x = normalize_input(batch["image"] ** 0.45, batch["mask"])
    if layout == "channels_last":
        x = x.contiguous(memory_format=torch.channels_last)
    weights = LossWeights(light_head=1.0 if net_cfg.light_mode == "hybrid" else 0.0)

    def step():
        opt.zero_grad(set_to_none=True)
        with torch.autocast("cpu", dtype=torch.bfloat16, enabled=precision == "bf16"):
            pred = model(x)
        relight_losses(pred, batch, weights)["total"].backward()
        opt.step()

    return median_ms(step, repeat=5, warmup=2)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--widths", default="16,32", help="network widths (max width 8x, light head 8x)")
    ap.add_argument("--modes", default="head,solve,hybrid")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    rows = []
    for width in (int(w) for w in args.widths.split(",")):
        for mode in args.modes.split(","):
            cfg = NetConfig(width=width, max_width=8 * width, light_hidden=8 * width, light_mode=mode)
            params = sum(p.numel() for p in RelightNet(cfg).parameters()) / 1e6
            base = None
            for precision in ("fp32", "bf16"):
                for layout in ("contiguous", "channels_last"):
                    ms = step_ms(cfg, args.size, args.batch, precision, layout)
                    base = base or ms
                    rows.append([f"{width} ({params:.1f} M)", mode, precision, layout, ms,
                                 args.batch / (ms * 1e-3), base / ms])
    print(f"{cpu_flags()}; threads {args.threads}; {args.size}², batch {args.batch}\n")
    print(table(["width (params)", "light", "precision", "layout", "ms/step", "samples/s", "speed-up"], rows))


if __name__ == "__main__":
    main()
