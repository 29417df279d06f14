"""SH core speed: env-map projection, rotating many lights, basis evaluation.

Run: ``.venv/bin/python benchmarks/bench_sh.py`` (2 threads). Prints a markdown table.
"memory floor" is the time to read the inputs and write the outputs once at the
copy bandwidth measured in the same run (256 MB buffers): a lower bound, far
below what these compute-bound jobs can reach, shown for scale.
"""

from __future__ import annotations

import os
import sys

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import median_ms, table  # noqa: E402

from relightnet.io.envmap import read_envmap  # noqa: E402
from relightnet.sh import project_envmap, rotate_sh, sh_basis  # noqa: E402


def copy_gbps() -> float:
    a = torch.empty(256 * 2**20, dtype=torch.uint8)
    b = torch.empty_like(a)
    ms = median_ms(lambda: b.copy_(a), repeat=5)
    return 2 * a.numel() / (ms * 1e-3) / 1e9


def main() -> None:
    torch.set_num_threads(2)
    gbps = copy_gbps()
    rows = []
    env = read_envmap(os.path.join(os.path.dirname(__file__), "..", "relightnet", "data", "envmaps", "sunset.exr"))
    h, w = env.shape[:2]
    for lmax in (2, 4):
        ms = median_ms(lambda lmax=lmax: project_envmap(env, lmax), repeat=5)
        floor = env.numel() * 4 / gbps / 1e6
        rows.append([f"project_envmap {w}x{h} -> lmax {lmax}", ms, floor, ms / floor])
    g = torch.Generator().manual_seed(0)
    R = torch.linalg.qr(torch.randn(1000, 3, 3, generator=g))[0]
    R = R * torch.sign(torch.linalg.det(R))[:, None, None]
    for lmax in (2, 4):
        k = (lmax + 1) ** 2
        sh = torch.randn(1000, k, 3, generator=g)
        ms = median_ms(lambda sh=sh: rotate_sh(sh, R), repeat=9)
        floor = (2 * sh.numel() + R.numel()) * 4 / gbps / 1e6
        rows.append([f"rotate_sh 1000 lights, lmax {lmax}", ms, floor, ms / floor])
    d = torch.nn.functional.normalize(torch.randn(1_000_000, 3, generator=g), dim=-1)
    for lmax in (2, 4):
        k = (lmax + 1) ** 2
        ms = median_ms(lambda lmax=lmax: sh_basis(d, lmax, check=False), repeat=5)
        floor = (d.numel() + d.shape[0] * k) * 4 / gbps / 1e6
        rows.append([f"sh_basis 1M dirs, lmax {lmax}", ms, floor, ms / floor])
        ms_c = median_ms(lambda lmax=lmax: sh_basis(d, lmax, check=True), repeat=5)
        rows.append([f"sh_basis 1M dirs, lmax {lmax}, with input checks", ms_c, floor, ms_c / floor])
    print(f"threads: {torch.get_num_threads()}, measured copy bandwidth: {gbps:.1f} GB/s\n")
    print(table(["job", "median ms", "memory floor ms", "x floor"], rows))


if __name__ == "__main__":
    main()
