"""Speed of the avatar job with the dressed avatar and --replace-person, at 1280x720.

The target is :func:`relightnet.pipeline.walk_target.walking_target` (Anny walking across a known,
textured background; x264 mp4). Each variant runs the whole ``avatar`` job (given light, so the CNN
pass is not measured; 64 PRT directions) in a fresh child process on ``--threads`` threads, for two
clip lengths; the steady-state frame rate is the slope (frames added / seconds added), which takes
the per-clip costs out (the outfit's texture and tables, the default albedo, the clean plate's
segmentation pass, writing the light files). Also printed: the per-clip setup and the clean plate's
PSNR against the true background over the pixels the person covered and uncovered.

    python benchmarks/bench_avatar_look.py                     # 1280x720, 8 and 24 frames, 2 threads
    python benchmarks/bench_avatar_look.py --frames 8 40 --runs 3
    python benchmarks/bench_avatar_look.py --only-outfit --avatar me.avatar.npz   # a captured person beside the outfit
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import table  # noqa: E402

VARIANTS = {"plain (smooth default albedo)": [], "outfit casual": ["--outfit", "casual"],
            "outfit casual + replace-person": ["--outfit", "casual", "--replace-person"]}


def child(target: str, frames: int, extra: list[str], threads: int, out: str) -> dict:
    """Run the avatar job on the first ``frames`` frames (a cut copy of the target); wall and CPU seconds."""
    import torch

    torch.set_num_threads(threads)
    from relightnet.cli import main

    t0, c0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_SELF)
    rc = main(["-q", "avatar", "--target", target, "--light", "studio", "--out", out, *extra])
    c1 = resource.getrusage(resource.RUSAGE_SELF)
    return {"rc": rc, "wall": time.perf_counter() - t0, "cpu": c1.ru_utime + c1.ru_stime - c0.ru_utime - c0.ru_stime}


def cut(src: Path, dst: Path, n: int) -> None:
    from relightnet.io import VideoWriter, read_video

    with VideoWriter(dst, fps=30) as w:
        for t, f in enumerate(read_video(src)):
            if t == n:
                break
            w.write(f)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="1280x720", help="W x H")
    ap.add_argument("--frames", type=int, nargs=2, default=(8, 24))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--avatar", help="also time a captured person (an avatar file from `relightnet capture`)")
    ap.add_argument("--only-outfit", action="store_true", help="time only the outfit (and --avatar) variants")
    ap.add_argument("--child", nargs=4, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.only_outfit:
        for k in [k for k in VARIANTS if k != "outfit casual"]:
            del VARIANTS[k]
    if a.avatar:
        VARIANTS["captured person (--avatar)"] = ["--avatar", str(Path(a.avatar).resolve())]
    if a.child:
        target, frames, extra, out = a.child
        print(json.dumps(child(target, int(frames), json.loads(extra), a.threads, out)))
        return
    W, H = (int(x) for x in a.size.split("x"))
    tmp = Path(tempfile.mkdtemp(prefix="bench_look_"))
    from relightnet.pipeline.clean_plate import clean_plate, plate_psnr
    from relightnet.pipeline.walk_target import walking_target

    n_max = max(a.frames)
    wt = walking_target(tmp / "walk", size=(H, W), n_frames=n_max, suffix=".mp4")
    clips = {n: tmp / f"t{n}.mp4" for n in a.frames}
    for n, p in clips.items():
        cut(wt.video, p, n)
    from relightnet.io import read_video

    true_masks = ((m[..., 0] > 127) for m in read_video(wt.masks))
    cp = clean_plate(zip(read_video(wt.video), true_masks, strict=False), n_max)
    psnr_true = plate_psnr(cp.plate, wt.background, wt.ever & ~wt.always & ~cp.flagged)
    env = dict(os.environ, PYTHONPATH=str(ROOT), OMP_NUM_THREADS=str(a.threads))
    res: dict = {}
    for r in range(a.runs):
        for name, extra in VARIANTS.items():
            for n, clip in clips.items():
                out = tmp / f"o_{r}_{n}_{len(extra)}.mp4"
                p = subprocess.run([sys.executable, __file__, "--threads", str(a.threads), "--child", str(clip), str(n),
                                    json.dumps(extra), str(out)], env=env, capture_output=True, text=True, check=True)
                d = json.loads(p.stdout.strip().splitlines()[-1])
                if d["rc"] != 0:
                    raise SystemExit(f"{name}: rc {d['rc']}: {p.stderr[-400:]}")
                res.setdefault(name, {}).setdefault(n, []).append(d)
                if "--replace-person" in extra and n == n_max and r == 0:
                    from relightnet.io import read_image

                    plate = (read_image(out.with_name(out.stem + ".plate.png")) * 255).round().byte().numpy()
                    res["psnr_segment"] = plate_psnr(plate, wt.background, wt.ever & ~wt.always & ~cp.flagged)
    n0, n1 = a.frames
    rows = []
    for name in VARIANTS:
        w0 = statistics.median(d["wall"] for d in res[name][n0])
        w1 = statistics.median(d["wall"] for d in res[name][n1])
        c0 = statistics.median(d["cpu"] for d in res[name][n0])
        c1 = statistics.median(d["cpu"] for d in res[name][n1])
        per, cper = (w1 - w0) / (n1 - n0), (c1 - c0) / (n1 - n0)
        rows.append([name, round(1 / per, 2), round(1000 * per), round(1000 * cper), round(w0 - n0 * per, 1),
                     " / ".join(f"{d['wall']:.1f}" for d in res[name][n1])])
    print(f"avatar job at {W}x{H}, {a.threads} threads, given light, 64 PRT directions; clips of {n0} and {n1} frames")
    print(table(["variant", "frames/s (steady)", "ms/frame", "CPU ms/frame", "setup s", f"wall s ({n1} frames)"],
                rows))
    if "psnr_segment" not in res:
        return
    print(f"\nclean plate PSNR over the pixels covered then uncovered ({n_max} frames): "
          f"{psnr_true:.1f} dB with the true masks, {res['psnr_segment']:.1f} dB with the segmentation's "
          f"(the job's); inpainted share {cp.inpainted_share:.3f}")


if __name__ == "__main__":
    main()
