"""3D-path speed: SH shading against the memory-bandwidth limit, and one full avatar frame.

Run: ``.venv/bin/python benchmarks/bench_render.py`` (2 threads, ANNY_CACHE_DIR set by make).

1. ``shade`` (albedo ⊙ (T·L)) on a 1024² frame, K = 9: bytes that must move (read T and
   A, write the image) over the copy bandwidth measured in the same run. Goal ≤ 1.3×.
2. A full frame at 512² — pose the Anny body → PRT transport (64 directions, occlusion)
   → rasterize → per-vertex shading interpolated + texture albedo → composite over a
   background — with the time of each stage. Goal ≤ 150 ms.
"""

from __future__ import annotations

import os
import sys
import time

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import median_ms, table  # noqa: E402

from relightnet.body import AnnyBody, default_albedo, make_motion  # noqa: E402
from relightnet.light import preset_light  # noqa: E402
from relightnet.prt import PrtSettings, vertex_transport  # noqa: E402
from relightnet.raster import default_camera  # noqa: E402
from relightnet.render.frame import TexturedAlbedo, render_mesh  # noqa: E402
from relightnet.render.shading import composite, shade  # noqa: E402


def copy_gbps() -> float:
    a = torch.empty(256 * 2**20, dtype=torch.uint8)
    b = torch.empty_like(a)
    return 2 * a.numel() / (median_ms(lambda: b.copy_(a), repeat=5) * 1e-3) / 1e9


def bench_shading() -> list:
    g = torch.Generator().manual_seed(0)
    A = torch.rand(1, 1024, 1024, 3, generator=g)
    T = torch.randn(1, 1024, 1024, 9, generator=g)
    L = torch.randn(9, 3, generator=g)
    rows = []
    for _ in range(3):  # interleave with the copy to share the machine's noise
        gbps = copy_gbps()
        ms = median_ms(lambda: shade(A, T, L), repeat=15)
        naive = median_ms(lambda: A * (T @ L), repeat=7)
        floor = (T.numel() + 2 * A.numel()) * 4 / (gbps * 1e9) * 1e3
        rows.append([gbps, floor, ms, ms / floor, naive, naive / floor])
    rows.sort(key=lambda r: r[3])
    return rows[len(rows) // 2]


def bench_frame(n: int = 9) -> list:
    body = AnnyBody()
    alb = default_albedo(body)
    tex = TexturedAlbedo(alb.texture, body.uv, body.uv_faces)
    light = preset_light("courtyard")
    cam = default_camera(512)
    bg = torch.rand(512, 512, 3)
    motion = make_motion("walk", n, seed=0)
    stages = {k: [] for k in ("pose", "transport", "raster+shade", "composite", "total")}
    for t in range(n):
        params = {"pose": {k: v[t : t + 1] for k, v in motion["pose"].items()}, "trans": motion["trans"][t : t + 1]}
        t0 = time.perf_counter()
        with torch.no_grad():
            out = body(params)
        t1 = time.perf_counter()
        T = vertex_transport(out.verts[0], out.faces, out.normals[0], lmax=2, prt=PrtSettings(n_dirs=64))
        t2 = time.perf_counter()
        r = render_mesh(out.verts[0], out.faces, T, tex, light, cam)
        t3 = time.perf_counter()
        composite(r.image, r.alpha, bg)
        t4 = time.perf_counter()
        for k, a, b in (("pose", t0, t1), ("transport", t1, t2), ("raster+shade", t2, t3), ("composite", t3, t4),
                        ("total", t0, t4)):
            stages[k].append((b - a) * 1e3)
    return [[k, sorted(v[1:])[len(v[1:]) // 2]] for k, v in stages.items()]  # drop the warm-up frame


def main() -> None:
    torch.set_num_threads(2)
    gbps, floor, ms, ratio, naive, naive_ratio = bench_shading()
    print(f"threads: {torch.get_num_threads()}, copy bandwidth {gbps:.1f} GB/s\n")
    print(table(["shade 1024², K=9", "median ms", "bandwidth floor ms", "x floor"],
                [["relightnet shade (grouped GEMM)", ms, floor, ratio],
                 ["naive A * (T @ L)", naive, floor, naive_ratio]]))
    print()
    print(table(["full 3D frame 512², Anny walk, 64 dirs", "median ms"], bench_frame()))


if __name__ == "__main__":
    main()
