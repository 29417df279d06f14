"""Person segmentation: IoU on generated people over real photographs and on scikit-image's
astronaut, flip rate and IoU of tracked masks on clips, and milliseconds per 720p frame on 2 threads.

Run: ``.venv/bin/python benchmarks/bench_segment.py [--people 8] [--frames 30] [--photos DIR]
[--video VIDEO MASKS] [--steady 0 0.15]`` (``--people 0``: the video table only).

Scenes: people made by the package's generator (Anny bodies with painted clothes, 512², train
split) composited at random sizes (50-92% of the frame height) and places into 1280 x 720
versions of scikit-image's real photographs (coffee, rocket, chelsea, motorcycle, brick; not camera, which shows a man);
the true mask is the composited coverage above one half. The clips: a generated person
walking while drifting right 13 px a frame over the coffee photo, and one turning in place
(90-360°, eased over the clip; where a tracked outline shimmers most against the few pixels a
turning silhouette changes) over the chelsea photo. Each clip is tracked once per ``--steady``
margin of the tracker's temporal mask filter (0: off; :mod:`relightnet.segment.steady`), the
previous mask carried along the landmarks' motion or along the optical flow; the flip rate is
compared with the true masks' (bound: 1.3×). The walking clip is also tracked with motion blur
(each frame the mean of itself and its neighbours). ``--video VIDEO MASKS``: real footage with
hand-made masks (bound: 1.5× their flips). The astronaut has no
true mask: it is reported by the share of its hand-picked person / background points that
come out right. Timing: photos (both stages: candidates + 2 refinements) and tracked video
frames (one pose-model read), medians.

``--photos DIR`` adds a real-pixel stand-in for real footage: each photo of a person in DIR is
filmed by a moving camera (slow pan and zoom with hand-held shake: sub-pixel translation and
rotation noise), 720 px high. The reference masks are the photo's own segmentation (at the
photo's size) carried by the same camera motion: a mask that moves exactly with the picture,
so every flip beyond the reference's is the tracker's own flicker (bound: 1.5×). The person does
not move (no limbs crossing, no motion blur): it measures flicker on real appearance, not on real motion.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "segment"))
from common import table  # noqa: E402
from people import background, flip_rate, iou, person_cutout, place  # noqa: E402

from relightnet.segment import PersonModels, PersonTracker, segment_person  # noqa: E402
from relightnet.segment.steady import STEADY_MARGIN  # noqa: E402

SIZE = (720, 1280)
BACKGROUNDS = ("coffee", "rocket", "chelsea", "motorcycle", "brick")


def photos(models, n_people: int, seed: int = 0):
    from relightnet.data import SynthConfig
    from relightnet.data.generate import assets_for, generate_sample

    assets = assets_for(None)
    rng = np.random.default_rng(seed)
    rows, times = [], []
    for i in range(n_people):
        person, cover = person_cutout(generate_sample(SynthConfig(res=512), "train", i, body=assets).arrays)
        for b in BACKGROUNDS[i % 2::2]:
            h = rng.uniform(0.5, 0.92)
            img, truth = place(background(b, SIZE), person, cover, h, rng.uniform(0.25, 0.75),
                               rng.uniform(h + 0.02, 0.99))
            t0 = time.perf_counter()
            try:
                m = segment_person(img, models).mask
            except ValueError:
                m = torch.zeros(SIZE)
            times.append((time.perf_counter() - t0) * 1e3)
            rows.append((i, b, h, iou(m, truth)))
    return rows, times


def _clip_frames(arrays: dict, bg: str, cx, height: float) -> tuple[list, list]:
    """A generated clip's person over a real photograph: frames and true masks (cx(t): the centre)."""
    ys, xs = np.nonzero(arrays["mask"].max(0) > 0.5)
    box = (slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1))
    back = background(bg, SIZE)
    frames, truth = [], []
    for t in range(len(arrays["mask"])):
        p, c = person_cutout({"image": arrays["image"][t], "mask": arrays["mask"][t]}, crop=box)
        img, m = place(back, p, c, height, cx(t), 0.95)
        frames.append(img)
        truth.append(m)
    return frames, truth


def walking(n_frames: int) -> tuple[list, list]:
    """The generated clip: a person walking while drifting right 13 px a frame over the coffee photo."""
    from relightnet.data import SynthConfig
    from relightnet.data.generate import assets_for, generate_sequence

    a = generate_sequence(SynthConfig(res=512), "train", 0, n_frames, body=assets_for(None)).arrays
    return _clip_frames(a, "coffee", lambda t: 0.35 + 0.01 * t, 0.8)


def turning(n_frames: int) -> tuple[list, list]:
    """The harder generated clip: a person turning in place (the fit benchmark's clip 2: a turn of
    90-360° eased over the clip, whole body, no noise) over the chelsea photo."""
    from relightnet.data.generate import assets_for, generate_sequence
    from relightnet.pipeline.fit_eval import fit_eval_config

    a = generate_sequence(fit_eval_config(3, n_frames, 512), "test", 2, n_frames, body=assets_for(None)).arrays
    return _clip_frames(a, "chelsea", lambda t: 0.5, 0.85)


def blurred(frames: list, truth: list) -> tuple[list, list]:
    """Motion blur: each frame the mean of itself and its two neighbours (the ends repeated); the true
    masks kept (the middle frame's)."""
    pad = [frames[0], *frames, frames[-1]]
    return [(pad[t] + pad[t + 1] + pad[t + 2]) / 3 for t in range(len(frames))], truth


def real_video(video: Path, masks: Path, n_frames: int) -> tuple[list, list]:
    """Real footage and its hand-made masks (a pixel > 127 is the person): the first ``n_frames``."""
    from itertools import islice

    from relightnet.io.video import read_video

    frames = [torch.from_numpy(f).permute(2, 0, 1).float() / 255 for f in islice(read_video(video), n_frames)]
    truth = [torch.from_numpy(m[..., 0] > 127).float() for m in islice(read_video(masks), n_frames)]
    return frames, truth


def track(models, frames: list, truth: list, steady: float, flow: bool = True):
    """(IoU per frame, flip rate tracked, flip rate true, ms per frame after the first) of the tracker."""
    tracker = PersonTracker(models, steady=steady, flow=flow)
    masks, times = [], []
    for f in frames:
        t0 = time.perf_counter()
        res = tracker(f)
        times.append((time.perf_counter() - t0) * 1e3)
        masks.append(torch.zeros(f.shape[1:]) if res is None else res.mask)
    ious = [iou(m, t) for m, t in zip(masks, truth, strict=True)]
    return ious, flip_rate(masks), flip_rate(truth), times[1:]  # frame 0 is a photo-style search


def _camera(t: int, rng: np.random.Generator) -> torch.Tensor:
    """(2, 3) affine_grid matrix of frame t: pan 0.3% of the width and zoom 0.25% a frame, shake."""
    s = 1.0 / (1.0 + 0.0025 * t)
    a = np.deg2rad(rng.normal(0.0, 0.15))
    dx, dy = 0.003 * t + rng.normal(0.0, 0.002), rng.normal(0.0, 0.002)
    return torch.tensor([[s * np.cos(a), -s * np.sin(a), dx], [s * np.sin(a), s * np.cos(a), dy]],
                        dtype=torch.float32)


def real_footage(models, path: Path, n_frames: int, seed: int = 0) -> tuple[list, list]:
    """Frames and reference masks of one photo filmed by a moving camera (module docstring)."""
    import torch.nn.functional as F

    from relightnet.io import read_image

    photo = read_image(path).permute(2, 0, 1)
    ref = segment_person(photo, models).mask
    h = 720
    w = round(photo.shape[2] * h / photo.shape[1] / 2) * 2
    rng = np.random.default_rng(seed)
    frames, truth = [], []
    for t in range(n_frames):
        grid = F.affine_grid(_camera(t, rng)[None], [1, 3, h, w], align_corners=False)
        frame = F.grid_sample(photo[None], grid, mode="bilinear", padding_mode="border", align_corners=False)[0]
        true = F.grid_sample(ref[None, None], grid, mode="bilinear", align_corners=False)[0, 0] > 0.5
        frames.append(frame.clamp(0, 1))
        truth.append(true.float())
    return frames, truth


def astronaut(models) -> float:
    from skimage import data

    img = torch.from_numpy(data.astronaut()).permute(2, 0, 1).float() / 255
    m = segment_person(img, models).mask
    person = ((225, 120), (230, 60), (150, 400), (250, 330), (100, 480), (300, 450))
    bg = ((20, 100), (480, 20), (400, 200), (330, 60), (60, 20), (470, 300))
    return (sum(int(m[y, x] == 1) for x, y in person) + sum(int(m[y, x] == 0) for x, y in bg)) / 12


def video_sets(models, args) -> list[tuple[str, list, list]]:
    """(name, frames, true or reference masks) of each video set the arguments ask for."""
    walk = walking(args.frames)
    sets = [("generated: walking, drifting right", *walk), ("generated: walking, motion blur", *blurred(*walk)),
            ("generated: turning in place", *turning(args.frames))]
    if args.video is not None:
        sets.append((f"real footage, hand-made masks: {args.video[0].name}",
                     *real_video(*args.video, args.video_frames)))
    if args.photos is not None:
        for p in sorted(args.photos.glob("*.jp*g")) + sorted(args.photos.glob("*.png")):
            sets.append((f"real photo, moving camera: {p.name[:19]}", *real_footage(models, p, args.frames)))
    return sets


def steadiness(models, args) -> None:
    """The flip-rate table: each video set tracked with each ``--steady`` margin."""
    rows = []
    for name, frames, truth in video_sets(models, args):
        for m in args.steady:
            for flow in (False, True) if m > 0 else (False,):
                ious, flips, true_flips, ms = track(models, frames, truth, m, flow)
                bound = 1.5 if name.startswith("real") else 1.3
                rows.append([name, f"{m} {'flow' if flow else 'landmarks'}" if m > 0 else "off", float(np.mean(ious)),
                             float(np.min(ious)), flips, true_flips, f"{flips / true_flips:.2f} (bound {bound})",
                             statistics.median(ms)])
    print(table(["video set", "steady: carried along", "IoU mean", "IoU min", "flips tracked", "flips true/reference",
                 "ratio", "ms per frame (median, 2 threads)"], rows))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--people", type=int, default=8, help="generated people over photos (0: skip the photos)")
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--photos", type=Path, default=None, help="folder of real photos of people (module docstring)")
    ap.add_argument("--steady", type=float, nargs="+", default=[0.0, STEADY_MARGIN],
                    help=f"the tracker's mask-filter margins to compare (default: 0 (off) and {STEADY_MARGIN})")
    ap.add_argument("--video", type=Path, nargs=2, metavar=("VIDEO", "MASKS"), default=None,
                    help="real footage and its hand-made mask video (a pixel > 127 is the person)")
    ap.add_argument("--video-frames", type=int, default=240, help="frames of --video to track")
    args = ap.parse_args()
    torch.set_num_threads(2)
    models = PersonModels(threads=2)
    if args.people > 0:
        rows, photo_ms = photos(models, args.people)
        ious = [r[3] for r in rows]
        print(table(["person", "background", "height", "IoU"], [list(r) for r in rows]))
        print(table(["set", "n", "IoU mean", "IoU median", "IoU min", "ms per 720p frame (median, 2 threads)"], [
            ["photos: generated people over real photos", len(ious), float(np.mean(ious)), float(np.median(ious)),
             float(np.min(ious)), statistics.median(photo_ms)]]))
        print(f"astronaut: {astronaut(models):.0%} of 12 hand-picked person/background points right")
    print()
    steadiness(models, args)
    weights = Path(__file__).resolve().parents[1] / "relightnet" / "weights"
    size = sum(f.stat().st_size for f in weights.glob("*.onnx"))
    print(f"shipped ONNX files: {size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
