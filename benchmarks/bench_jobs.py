"""The two jobs users wait for, end to end beside their codec floor, and stage by stage.

Run: ``.venv/bin/python benchmarks/bench_jobs.py [--photo P.jpg] [--video V.mp4] [--frames 90] [--repeat 3]``

Default inputs: the development material in ``../shared`` when it is there (a 5.1 MP JPEG of a
person, a 720×940 H.264 clip of a person turning), else a generated person (``--photo``/``--video``
name any others). In one run:

1. ``relightnet relight-image PHOTO --light sunset --out X.png`` as a user runs it (a new process,
   median wall of ``--repeat``), beside the photo's floor: decoding it and writing the PNG with the
   package's writer, in one process that has already imported them. ``relightnet --help`` and the
   first import of the relight path (a new process each) beside them.
2. ``relightnet relight-video`` on the clip's first ``--frames`` frames at its own size, at 720p and
   at 1080p (the clip scaled to the height and padded to 16:9), beside the floor: decoding the same
   clip and encoding it with the package's writer. Frames/s and the ratio.
3. The stages of both jobs in one process (the same functions the commands call, each timed where
   it is called): start-up, decode, segmentation, framing + CNN, relight, soft edges, encode.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
CLI = [sys.executable, "-m", "relightnet", "-q"]


def _wall(cmd: list[str], repeat: int) -> float:
    """Median wall seconds of a command in a new process (each run must succeed)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _generated_photo(path: Path) -> Path:
    """A 2808×1866 JPEG of a generated person over a textured background (when no photo is given)."""
    import numpy as np
    import torch
    import torch.nn.functional as F

    from relightnet.data import SynthConfig, generate_sample

    a = generate_sample(SynthConfig(res=512, n_dirs=16), "test", 3).arrays
    img = torch.from_numpy(a["image_srgb"]).permute(2, 0, 1).float()[None] / 255
    big = F.interpolate(img, size=(1866, 1866), mode="bilinear", align_corners=False)[0]
    out = torch.full((3, 1866, 2808), 0.45)
    out[:, :, 471:2337] = big
    from PIL import Image

    Image.fromarray((out.permute(1, 2, 0).numpy() * 255).astype(np.uint8)).save(path, quality=92)
    return path


def _clip(src: Path, dst: Path, frames: int, height: int | None) -> Path:
    """The first ``frames`` frames of ``src`` as H.264, scaled to ``height`` and padded to 16:9 (None: as it is)."""
    import numpy as np
    import torch
    import torch.nn.functional as F

    from relightnet.io import VideoWriter, read_video, video_info

    fps = video_info(src).fps
    with VideoWriter(dst, fps=fps, srgb=False) as w:
        for t, f in enumerate(read_video(src)):
            if t >= frames:
                break
            if height is not None:
                x = torch.from_numpy(f).permute(2, 0, 1).float()[None]
                h, wd = f.shape[:2]
                x = F.interpolate(x, size=(height, round(wd * height / h) // 2 * 2), mode="bilinear",
                                  align_corners=False)[0]
                canvas = torch.full((3, height, height * 16 // 9), 110.0)
                x0 = (canvas.shape[2] - x.shape[2]) // 2
                canvas[:, :, x0:x0 + x.shape[2]] = x
                f = canvas.clamp(0, 255).round().to(torch.uint8).permute(1, 2, 0).numpy()
            w.write(torch.from_numpy(np.ascontiguousarray(f)))
    return dst


def _codec_floor_video(path: Path, out: Path) -> float:
    """Seconds to decode ``path`` and encode its frames with the package's writer (one process, warm)."""
    import torch

    from relightnet.io import VideoWriter, read_video, video_info

    t0 = time.perf_counter()
    with VideoWriter(out, fps=video_info(path).fps, srgb=False) as w:
        for f in read_video(path):
            w.write(torch.from_numpy(f))
    return time.perf_counter() - t0


def _codec_floor_photo(path: Path, out: Path, repeat: int) -> float:
    from relightnet.io import read_image_alpha, write_image

    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        img, _ = read_image_alpha(path)
        write_image(out, img, srgb=False)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def end_to_end(photo: Path, video: Path, frames: int, repeat: int, d: Path) -> None:
    job = _wall(CLI + ["relight-image", str(photo), "--light", "sunset", "--out", str(d / "r.png")], repeat)
    floor = _codec_floor_photo(photo, d / "floor.png", repeat)
    helps = _wall([sys.executable, "-m", "relightnet", "--help"], repeat)
    imp = _wall([sys.executable, "-c", "import relightnet.pipeline.relight_image, relightnet.pipeline.backends, "
                 "relightnet.segment.sources"], repeat)
    torch_only = _wall([sys.executable, "-c", "import torch"], repeat)
    print(f"\nphoto {photo.name}: relight-image end to end vs its decode + encode floor\n")
    print(table(["what", "s", "× floor"], [["relight-image --light sunset (wall)", job, job / floor],
                                          ["floor: decode + PNG encode", floor, 1.0],
                                          ["relightnet --help (wall)", helps, ""],
                                          ["import of the relight path (wall, new process)", imp, ""],
                                          ["import torch alone (wall, new process)", torch_only, ""]]))
    rows = []
    for label, height in (("source", None), ("720p", 720), ("1080p", 1080)):
        clip = _clip(video, d / f"clip_{label}.mp4", frames, height)
        wall = _wall(CLI + ["relight-video", str(clip), "--light", "sunset", "--out", str(d / "rv.mp4")],
                     max(1, repeat // 2))
        fl = _codec_floor_video(clip, d / "floor.mp4")
        rows.append([f"{label} ({_size(clip)})", frames / wall, frames / fl, wall / fl])
    print(f"\nvideo {video.name}, first {frames} frames: relight-video end to end vs decode + encode\n")
    print(table(["clip", "relight-video frames/s", "floor frames/s", "× floor"], rows))


def _size(path: Path) -> str:
    from relightnet.io import video_info

    i = video_info(path)
    return f"{i.size[1]}×{i.size[0]}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--photo", type=Path)
    ap.add_argument("--video", type=Path)
    ap.add_argument("--frames", type=int, default=90)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--stages-only", action="store_true", help="skip the end-to-end runs")
    args = ap.parse_args()
    import torch
    from bench_job_stages import photo_stages, video_stages

    print(f"CPU: {_cpu()}; torch {torch.__version__}, {torch.get_num_threads()} threads")
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        photo = args.photo or next(iter(sorted((SHARED / "real-photos").glob("photo-1521056569365*.jpg"))), None) \
            or _generated_photo(d / "generated.jpg")
        video = args.video or (SHARED / "real-video" / "turning.mp4")
        if not video.is_file():
            raise SystemExit(f"{video}: no clip; give --video")
        if not args.stages_only:
            end_to_end(photo, video, args.frames, args.repeat, d)
        photo_stages(photo, d)
        for label, height in (("720p", 720), ("source", None)):
            clip = d / f"clip_{label}.mp4"
            if not clip.exists():
                _clip(video, clip, args.frames, height)
            video_stages(clip, d, label)


def _cpu() -> str:
    with open("/proc/cpuinfo") as f:
        return next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), "unknown")


if __name__ == "__main__":
    main()
