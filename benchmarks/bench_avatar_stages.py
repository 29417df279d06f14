"""Speed of the avatar job (the 3D path) at a real video's size: per stage and end to end, optionally
side by side with another copy of the package (before/after a change, runs interleaved).

The target stands in for a real clip: Anny turning (not the avatar's walk) over a panning view of a
real photograph (the shipped courtyard HDRI, tone-mapped), x264 mp4 plus a mask video (mp4). Every
measurement runs in a fresh child process on ``--threads`` threads (torch, and the CPUs the ray
engine may use); the table gives medians over frames (stages) or runs (end to end) and the child's
CPU time (all threads) per frame, which a busy machine disturbs less than wall time.

    python benchmarks/bench_avatar_stages.py                         # 720x940 (W x H), 60 frames
    python benchmarks/bench_avatar_stages.py --size 1280x720 --runs 5
    git archive main relightnet | tar -x -C /tmp/main_pkg            # the package before a change
    python benchmarks/bench_avatar_stages.py --baseline /tmp/main_pkg
"""

from __future__ import annotations

import argparse
import inspect
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

STAGES = ["decode frame", "pose body (chunks of 16)", "rasterize", "seen vertices", "PRT at seen vertices",
          "  of which: BVH build", "shade + interpolate + texture", "composite", "encode (mp4, x264)"]


def make_target(path: Path, h: int, w: int, frames: int) -> Path:
    """Write the stand-in clip (and ``*.masks.mp4`` beside it); returns the mask video."""
    import torch
    import torch.nn.functional as F

    from relightnet.body import AnnyBody, make_motion
    from relightnet.color import linear_to_srgb
    from relightnet.io import VideoWriter
    from relightnet.io.envmap import read_envmap
    from relightnet.light import preset_light
    from relightnet.pipeline.scene import avatar_albedo
    from relightnet.prt import PrtSettings
    from relightnet.raster import default_camera
    from relightnet.render import render_body_frames

    env = read_envmap(ROOT / "relightnet" / "data" / "envmaps" / "courtyard.exr")
    env = env / env.flatten().quantile(0.95)
    env = F.interpolate(env.permute(2, 0, 1)[None], size=(2 * h, w + 4 * frames), mode="bilinear")[0]
    env = linear_to_srgb(env.permute(1, 2, 0).clamp(0, 1))
    body = AnnyBody()
    person = render_body_frames(body, make_motion("turn", frames), preset_light("sunset"), avatar_albedo(body),
                                camera=default_camera((h, w), distance=2.6), n_frames=frames,
                                prt=PrtSettings(n_dirs=16), visible_only=True)
    masks = path.with_name(path.stem + ".masks.mp4")
    with VideoWriter(path, fps=30, srgb=False) as v, VideoWriter(masks, fps=30) as m:
        for t, fr in enumerate(person):
            a = fr.render.alpha[0][..., None]
            bg = env[h // 2: h // 2 + h, 4 * t: 4 * t + w]
            v.write(linear_to_srgb(fr.render.image[0].clamp(0, 1)) * a + bg * (1 - a))
            m.write((a.expand(h, w, 3) * 255).to(torch.uint8).numpy())
    return masks


def _cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def child_e2e(args) -> dict:
    """One run of the job; wall and CPU seconds (loading the model and the body excluded)."""
    from relightnet.body import AnnyBody
    from relightnet.light import preset_light
    from relightnet.pipeline import AvatarLook, avatar, make_predictor
    from relightnet.prt import PrtSettings

    body = AnnyBody()
    model = make_predictor("torch") if args.mode == "estimate" else None
    light = preset_light("studio") if args.mode == "light" else None
    masks = args.target.with_name(args.target.stem + ".masks.mp4") if args.mode == "estimate" else None
    with tempfile.TemporaryDirectory() as d:
        c0, t0 = _cpu_s(), time.perf_counter()
        res = avatar(args.target, Path(d) / "out.mp4", model=model, look=AvatarLook(body=body), light=light,
                     target_masks=masks, prt=PrtSettings(n_dirs=args.n_dirs), progress=False)
        return {"frames": res.n_frames, "wall": time.perf_counter() - t0, "cpu": _cpu_s() - c0}


def child_stages(args) -> dict:
    """Median wall and CPU ms per frame of each step the job takes, over the clip's frames."""
    import numpy as np
    import torch

    from relightnet.body import AnnyBody, make_motion
    from relightnet.io import VideoWriter, read_video
    from relightnet.light import preset_light
    from relightnet.pipeline.scene import avatar_albedo
    from relightnet.prt import vertex_transport
    from relightnet.prt.visibility import make_engine
    from relightnet.raster import Fragments, default_camera, rasterize
    from relightnet.render import render_mesh

    n = args.stage_frames
    video = read_video(args.target)
    bgs, times = [], {s: [] for s in STAGES}

    def timed(stage, fn, *a, **k):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn(*a, **k)
        times[stage].append(((time.perf_counter() - t0) * 1e3, (time.process_time() - c0) * 1e3))
        return out

    for _ in range(n):
        bgs.append(timed(STAGES[0], lambda: next(video)))
    body = AnnyBody()
    motion = make_motion("walk", 16)
    for _ in range(3):
        t0, c0 = time.perf_counter(), time.process_time()
        out = body(motion)
        times[STAGES[1]].append(((time.perf_counter() - t0) * 1e3 / 16, (time.process_time() - c0) * 1e3 / 16))
    faces = out.faces
    h, w = bgs[0].shape[:2]
    cam, tex, light = default_camera((h, w)), avatar_albedo(body), preset_light("studio")
    new_seen = hasattr(Fragments, "seen_vertices")
    opts = {"manifold": "ignore"} if "manifold" in inspect.signature(vertex_transport).parameters else {}
    try:
        from relightnet.pipeline.avatar import _composite_covered as composite
    except ImportError:
        from relightnet.color import linear_to_srgb
        from relightnet.io.image import to_uint8

        def composite(r, bg):
            a = r.alpha[0][..., None]
            comp = linear_to_srgb(r.image[0].clamp(0, 1)) * a + torch.from_numpy(bg).float() / 255 * (1 - a)
            return to_uint8(comp, srgb=False).numpy()
    with tempfile.TemporaryDirectory() as d, VideoWriter(Path(d) / "e.mp4", fps=30, srgb=False) as wr:
        for i in range(n):
            v, nrm = out.verts[i % 16], out.normals[i % 16]
            frags = timed(STAGES[2], rasterize, cam.transform(v), faces, cam.size)
            seen = (timed(STAGES[3], frags.seen_vertices, faces, v.shape[0]) if new_seen
                    else timed(STAGES[3], lambda f: torch.unique(faces[torch.unique(f.pix_face)]), frags))
            T = timed(STAGES[4], vertex_transport, v, faces, nrm, n_dirs=args.n_dirs, vertices=seen, **opts)
            timed(STAGES[5], make_engine, v, faces)
            r = timed(STAGES[6], render_mesh, v, faces, T, tex, light, cam, normals=nrm, frags=frags)
            frame = timed(STAGES[7], composite, r, bgs[i])
            timed(STAGES[8], wr.write, np.ascontiguousarray(frame))
    return {s: [statistics.median(t[0] for t in x), statistics.median(t[1] for t in x)] for s, x in times.items()}


def run_child(kind: str, pkg: Path, args, mode: str = "light") -> dict:
    env = dict(os.environ, PYTHONPATH=str(pkg), OMP_NUM_THREADS=str(args.threads))
    cmd = [sys.executable, __file__, "--child", kind, "--mode", mode, "--target", str(args.target),
           "--threads", str(args.threads), "--n-dirs", str(args.n_dirs), "--stage-frames", str(args.stage_frames)]
    res = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    if res.returncode:
        raise RuntimeError(f"{kind} child ({pkg}) failed:\n{res.stderr[-3000:]}")
    out = json.loads(res.stdout.strip().splitlines()[-1])
    sys.stderr.write(f"{kind} {mode} {pkg}: {json.dumps(out)}\n")  # progress: runs take minutes on a busy machine
    return out


def _size(s: str) -> tuple[int, int]:
    w, h = s.lower().split("x")
    return int(h), int(w)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="720x940", help="W x H of the target (default: 720x940)")
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--n-dirs", type=int, default=64)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", type=int, default=3, help="rounds: end-to-end runs (first mode) and stage runs")
    ap.add_argument("--modes", default="light,estimate",
                    help="light: given (the 3D path alone); estimate: the CNN estimates it (once per package)")
    ap.add_argument("--stage-frames", type=int, default=12)
    ap.add_argument("--baseline", type=Path, help="a folder holding another copy of the relightnet package")
    ap.add_argument("--target", type=Path, help="use this target video (with TARGET.masks.mp4 for estimation); "
                    "made there first (kept) when missing")
    ap.add_argument("--child", choices=("e2e", "stages"), help=argparse.SUPPRESS)
    ap.add_argument("--mode", choices=("light", "estimate"), default="light", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        import torch

        cpus = sorted(os.sched_getaffinity(0))
        if len(cpus) > args.threads:  # the ray engine uses the CPUs it may run on
            os.sched_setaffinity(0, cpus[: args.threads])
        torch.set_num_threads(args.threads)
        print(json.dumps(child_e2e(args) if args.child == "e2e" else child_stages(args)))
        return
    h, w = _size(args.size)
    with tempfile.TemporaryDirectory() as tmp:
        if args.target is None or not args.target.exists():
            args.target = args.target or Path(tmp) / f"target_{w}x{h}.mp4"
            sys.path.insert(0, str(ROOT))
            make_target(args.target, h, w, args.frames)
        pkgs = ([("before", args.baseline.resolve())] if args.baseline else []) + [("this", ROOT)]
        modes = args.modes.split(",")
        stages = {name: [] for name, _ in pkgs}
        runs = {(name, mode): [] for mode in modes for name, _ in pkgs}
        for r in range(args.runs):  # interleaved, so both packages see the same machine load
            for mode in modes if r == 0 else modes[:1]:
                for name, pkg in pkgs:
                    runs[name, mode].append(run_child("e2e", pkg, args, mode))
            for name, pkg in pkgs:
                stages[name].append(run_child("stages", pkg, args))
        report(args, pkgs, runs, stages, h, w)


def report(args, pkgs, runs, stages, h, w) -> None:
    cpu = open("/proc/cpuinfo").read().split("model name")[1].split("\n")[0].strip(": \t")
    n = next(iter(runs.values()))[0]["frames"]
    print(f"avatar job, target {w}x{h} (W x H), {n} frames, PRT {args.n_dirs} directions, "
          f"{args.threads} threads, {cpu}; {args.runs} interleaved runs (the estimated light: 1)\n")
    rows = []
    for (name, mode), rs in runs.items():
        fps = sorted(r["frames"] / r["wall"] for r in rs)
        cpu_ms = statistics.median(1e3 * r["cpu"] / r["frames"] for r in rs)
        rows.append([name, "given" if mode == "light" else "estimated", f"{statistics.median(fps):.2f}",
                     f"{1e3 / statistics.median(fps):.0f}", f"{cpu_ms:.0f}", " / ".join(f"{x:.2f}" for x in fps)])
    print(table(["package", "light", "frames/s", "ms/frame", "CPU ms/frame", "all runs (frames/s)"], rows))
    if args.baseline:
        for mode in {m for _, m in runs}:
            b, t = runs["before", mode], runs["this", mode]
            wall = statistics.median(x["wall"] / y["wall"] for x, y in zip(b, t, strict=True))
            cpu = statistics.median(x["cpu"] / y["cpu"] for x, y in zip(b, t, strict=True))
            print(f"\nbefore / this ({mode} light, median over rounds): wall {wall:.2f}x, CPU {cpu:.2f}x")
    print(f"\nPer stage (ms per frame: median over {args.stage_frames} frames, then over {args.runs} runs)\n")
    names = [n for n, _ in pkgs]
    med = {(n, s, i): statistics.median(r[s][i] for r in stages[n]) for n in names for s in STAGES for i in (0, 1)}
    srows = [[s] + [f"{med[n, s, i]:.1f}" for n in names for i in (0, 1)] for s in STAGES]
    srows.append(["sum (the BVH row is inside PRT)"]
                 + [f"{sum(med[n, s, i] for s in STAGES if not s.startswith(' ')):.0f}" for n in names for i in (0, 1)])
    print(table(["stage"] + [f"{k} ms ({n})" for n in names for k in ("wall", "CPU")], srows))


if __name__ == "__main__":
    main()
