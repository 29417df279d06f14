"""relightnet's PRT render vs Cycles (Blender 5.0.1, CPU) for one Anny avatar frame.

Run: ``.venv/bin/python benchmarks/bench_blender.py [--size 192] [--spp 256] [--n-dirs 256]
[--light city] [--pose arms_crossed] [--bounces 0,1,2] [--repeat 3] [--threads 2]
[--png /tmp/blender_reference.png]`` (needs the ``relightnet[blender]`` extra; ANNY_CACHE_DIR
defaults to ``.cache/anny``). The defaults take about 1–2 minutes on 2 cores; e.g.
``--size 256 --spp 1024 --n-dirs 1024`` for a cleaner reference.

For each bounce count B (PRT interreflection bounces = Cycles diffuse bounces) the table shows
the masked relative RMSE of relightnet's render (÷ π, see ``relightnet.blender.cycles``)
against Cycles lit by the SH-band-limited world (the order-2 projection of the map, lifted
to be non-negative; relightnet renders the same lifted light: PRT error + Cycles noise),
and against Cycles lit by the full environment map (relightnet renders the plain order-2
projection: adds what order-2 SH loses). Cycles' noise (two seeds, ÷√2) is printed above the
table. "front" columns leave out pixels whose interpolated normal faces away from the camera.
Times per frame are medians (ours: ``--repeat`` runs after a warm-up; Cycles: one render after a
1-spp warm-up, ``--cycles-repeat`` for more): ours = PRT transport + rasterize/shade
(the per-pose cost of the 3D path), Cycles = ``bpy.ops.render.render`` (scene sync, BVH,
path tracing; kernels warmed up once before).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
os.environ.setdefault("ANNY_CACHE_DIR", str(Path(__file__).resolve().parents[1] / ".cache" / "anny"))
from common import table  # noqa: E402

from relightnet.blender import CyclesSettings  # noqa: E402
from relightnet.blender.reference import reference_comparison  # noqa: E402
from relightnet.body import AnnyBody  # noqa: E402
from relightnet.prt import PrtSettings  # noqa: E402


def _pct(x: float) -> str:
    return f"{100 * x:.2f}%"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=192, help="square image size (default 192)")
    ap.add_argument("--spp", type=int, default=256, help="Cycles samples per pixel (default 256)")
    ap.add_argument("--n-dirs", type=int, default=256, help="PRT directions (default 256)")
    ap.add_argument("--light", default="city", help="preset or .exr/.hdr environment map (default city)")
    ap.add_argument("--pose", default="arms_crossed", help="Anny pose preset (default arms_crossed)")
    ap.add_argument("--bounces", default="0,1,2", help="comma-separated bounce counts (default 0,1,2)")
    ap.add_argument("--repeat", type=int, default=3, help="timing repeats of ours, medians (default 3)")
    ap.add_argument("--cycles-repeat", type=int, default=1, help="timing repeats of Cycles, medians (default 1)")
    ap.add_argument("--threads", type=int, default=2, help="torch and Cycles threads (default 2)")
    ap.add_argument("--png", help="also write ours | Cycles SH | Cycles env (last bounce count) side by side here")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    body = AnnyBody()
    bounces = [int(b) for b in args.bounces.split(",")]
    r = reference_comparison(body, {"pose": body.pose(args.pose)}, light=args.light, bounces=bounces, size=args.size,
                             cycles=CyclesSettings(spp=args.spp, threads=args.threads),
                             prt=PrtSettings(n_dirs=args.n_dirs), repeat=args.repeat, cycles_repeat=args.cycles_repeat)
    s = r.settings
    print(f"relightnet PRT vs Cycles: Anny '{args.pose}', light '{args.light}' (order-2 SH; lift "
          f"{', '.join(f'{x:.3f}' for x in s['lift'])}), {args.size}² px, {args.spp} spp, {args.n_dirs} PRT dirs, "
          f"{args.threads} threads; {s['pixels']} compared px ({s['front_pixels']} front-facing); "
          f"Cycles noise {_pct(r.noise)}\n")
    rows = []
    for row in r.rows:
        rows.append([row["bounces"], _pct(row["vs_sh"]), _pct(row["vs_sh_front"]), _pct(row["vs_env"]),
                     _pct(row["vs_env_front"]), f"{1e3 * row['ours_s']:.0f}",
                     f"{row['cycles_sh_s']:.2f}", f"{row['cycles_env_s']:.2f}",
                     f"{row['cycles_env_s'] / row['ours_s']:.1f}×"])
    print(table(["bounces", "ours vs Cycles SH world", "(front)", "ours vs Cycles env map", "(front)",
                 "ours ms/frame", "Cycles SH s/frame", "Cycles env s/frame",
                 "Cycles env / ours time"], rows))
    if args.png:
        from relightnet.io import write_image
        from relightnet.light.visualize import auto_exposure

        b = bounces[-1]
        imgs = [r.ours[b], r.cycles_sh[b][..., :3], r.cycles_env[b][..., :3]]
        scale = auto_exposure(imgs[2], r.mask)
        write_image(args.png, torch.cat(imgs, dim=1) * scale)
        print(f"\nwrote {args.png}")


if __name__ == "__main__":
    main()
