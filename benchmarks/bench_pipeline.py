"""End-to-end frames/s of the video jobs (relight-video: torch/onnx; avatar: torch/onnx) and the
split of the avatar job per stage, at 512² by default.

The target clip is a generated person (the data generator, a few frames played back and forth
to the wanted length) written as a lossless mkv with a mask video beside it.

    python benchmarks/bench_pipeline.py                      # 240 frames at 512², all jobs (3 runs) + stages
    python benchmarks/bench_pipeline.py --job avatar --frames 1000 --size 256   # one job (for /usr/bin/time -v)
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import median_ms, table  # noqa: E402


def make_clip(d: Path, size: int, frames: int, src_frames: int = 8):
    """A person clip of ``frames`` frames (``src_frames`` generated, played back and forth)."""
    from relightnet.body import AnnyBody
    from relightnet.data import SynthConfig, generate_sequence
    from relightnet.io import VideoWriter

    s = generate_sequence(SynthConfig(res=size, n_dirs=16), "test", 2, src_frames, body=AnnyBody())
    cyc = list(range(src_frames)) + list(range(src_frames - 2, 0, -1))
    video, masks = d / f"clip{size}_{frames}.mkv", d / f"masks{size}_{frames}.mkv"
    with VideoWriter(video, fps=30) as v, VideoWriter(masks, fps=30) as m:
        for t in range(frames):
            i = cyc[t % len(cyc)]
            v.write(s.arrays["image_composite"][i])
            m.write(np.repeat(s.arrays["mask"][i][..., None] * 255, 3, -1).astype(np.uint8))
    return video, masks


def run_job(job: str, backend: str, video, masks, out: Path, n_dirs: int) -> float:
    """Wall seconds of one job, end to end (loading the model and the body model excluded).

    Every run writes a fresh output, so the avatar never reuses earlier light estimates.
    """
    from relightnet.body import AnnyBody
    from relightnet.light import preset_light
    from relightnet.pipeline import AvatarLook, avatar, make_predictor, relight_video
    from relightnet.prt import PrtSettings

    pred = make_predictor(backend)
    body = AnnyBody() if job == "avatar" else None
    run = Path(tempfile.mkdtemp(dir=out))
    t0 = time.perf_counter()
    if job == "avatar":
        res = avatar(video, run / "avatar.mkv", model=pred, look=AvatarLook(body=body), target_masks=masks,
                     prt=PrtSettings(n_dirs=n_dirs), progress=False)
        if res.reused_estimates:
            raise RuntimeError("the benchmark must not reuse light estimates")
    else:
        relight_video(pred, video, masks, preset_light("sunset"), run / "relit.mkv", progress=False)
    seconds = time.perf_counter() - t0
    shutil.rmtree(run)
    return seconds


def stages(video, masks, n_dirs: int) -> list[list]:
    """Median ms per frame of each stage of the avatar job."""
    from relightnet.body import AnnyBody, make_motion
    from relightnet.io import VideoWriter, read_video
    from relightnet.io.video_masks import read_masks
    from relightnet.pipeline import make_predictor
    from relightnet.pipeline.avatar import _composite_covered
    from relightnet.pipeline.scene import avatar_albedo
    from relightnet.prt import PrtSettings, vertex_transport
    from relightnet.raster import default_camera, rasterize
    from relightnet.render import render_mesh
    from relightnet.temporal import smooth_video_lights

    frames = [f for _, f in zip(range(4), read_video(video), strict=False)]
    mask = next(read_masks(masks)[1])
    img = torch.from_numpy(frames[0]).permute(2, 0, 1).float() / 255
    h, w = frames[0].shape[:2]
    rows = []
    rows.append(["decode frame", median_ms(lambda: next(iter(read_video(video))), repeat=5)])
    for backend in ("torch", "onnx"):
        p = make_predictor(backend)
        rows.append([f"light estimate ({backend})", median_ms(lambda p=p: p.light(img, mask), repeat=7)])
    raw = torch.randn(48, 9, 3) * 0.1 + 1
    rows.append(["smoothing (48 frames, per frame)", median_ms(lambda: smooth_video_lights(raw), repeat=5) / 48])
    body = AnnyBody()
    motion = make_motion("walk", 16)
    rows.append(["pose body (per frame, chunks of 16)", median_ms(lambda: body(motion), repeat=3) / 16])
    out = body({"pose": {k: v[:1] for k, v in motion["pose"].items()}, "trans": motion["trans"][:1]})
    v, n, f = out.verts[0], out.normals[0], out.faces
    rows.append([f"PRT transport ({n_dirs} dirs, occlusion)", median_ms(
        lambda: vertex_transport(v, f, n, prt=PrtSettings(n_dirs=n_dirs)), repeat=5)])
    cam = default_camera((h, w))
    seen = rasterize(cam.transform(v), f, cam.size).seen_vertices(f, len(v))
    rows.append([f"PRT transport, visible vertices only ({len(seen)} of {len(v)}; the job's)", median_ms(
        lambda: vertex_transport(v, f, n, prt=PrtSettings(n_dirs=n_dirs), vertices=seen, manifold="ignore"), repeat=5)])
    T = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=n_dirs))
    tex, light = avatar_albedo(body), torch.rand(9, 3) * 0.2
    rows.append(["rasterize + shade (the job rasterizes once, before PRT)",
                 median_ms(lambda: render_mesh(v, f, T, tex, light, cam, normals=n), repeat=5)])
    r = render_mesh(v, f, T, tex, light, cam, normals=n)
    rows.append(["composite (8-bit, covered pixels)", median_ms(lambda: _composite_covered(r, frames[0]), repeat=7)])
    x = _composite_covered(r, frames[0])
    with tempfile.TemporaryDirectory() as d:
        with VideoWriter(Path(d) / "e.mp4", fps=30, srgb=False) as wr:
            rows.append(["encode (mp4, x264)", median_ms(lambda: wr.write(x), repeat=10)])
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--frames", type=int, default=240)
    ap.add_argument("--n-dirs", type=int, default=64)
    ap.add_argument("--job", choices=("all", "avatar", "relight-video"), default="all")
    ap.add_argument("--backend", choices=("torch", "onnx"), default="torch")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each job (the median is reported)")
    args = ap.parse_args()
    os.environ.setdefault("RELIGHTNET_CACHE", str(Path(tempfile.gettempdir()) / "relightnet-bench-cache"))
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        video, masks = make_clip(d, args.size, args.frames)
        if args.job != "all":
            s = run_job(args.job, args.backend, video, masks, d, args.n_dirs)
            rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            print(f"{args.job} ({args.backend}) {args.frames} frames at {args.size}²: {s:.1f} s, "
                  f"{args.frames / s:.2f} frames/s, peak RSS {rss:.0f} MiB")
            return
        rows = []
        for job in ("relight-video", "avatar"):
            for backend in ("torch", "onnx"):
                runs = sorted(run_job(job, backend, video, masks, d, args.n_dirs) for _ in range(args.repeat))
                s = runs[len(runs) // 2]
                rows.append([job, backend, args.frames, f"{args.frames / s:.2f}", f"{1000 * s / args.frames:.0f}",
                             " / ".join(f"{args.frames / r:.2f}" for r in runs)])
        print(f"End to end, {args.size}², {args.frames} frames, PRT {args.n_dirs} directions, "
              f"{torch.get_num_threads()} threads, median of {args.repeat} runs\n")
        print(table(["job", "backend", "frames", "frames/s", "ms/frame", "all runs (frames/s)"], rows))
        print(f"\nAvatar job per stage ({args.size}², median ms per frame)\n")
        print(table(["stage", "ms"], stages(video, masks, args.n_dirs)))


if __name__ == "__main__":
    main()
