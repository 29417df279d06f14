"""Person segmentation: IoU on generated people over real photographs and on scikit-image's
astronaut, flip rate on a clip, and milliseconds per 720p frame on 2 threads.

Run: ``.venv/bin/python benchmarks/bench_segment.py [--people 8] [--frames 30]``.

Scenes: people made by the package's generator (Anny bodies with painted clothes, 512², train
split) composited at random sizes (50-92% of the frame height) and places into 1280 x 720
versions of scikit-image's real photographs (coffee, rocket, chelsea, motorcycle, brick; not camera, which shows a man);
the true mask is the composited coverage above one half. The clip: a generated person
walking while drifting right 13 px a frame over the coffee photo. The astronaut has no
true mask: it is reported by the share of its hand-picked person / background points that
come out right. Timing: photos (both stages: candidates + 2 refinements) and tracked video
frames (one pose-model read), medians.
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


def clip(models, n_frames: int):
    from relightnet.data import SynthConfig
    from relightnet.data.generate import assets_for, generate_sequence

    a = generate_sequence(SynthConfig(res=512), "train", 0, n_frames, body=assets_for(None)).arrays
    ys, xs = np.nonzero(a["mask"].max(0) > 0.5)
    box = (slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1))
    bg = background("coffee", SIZE)
    frames, truth = [], []
    for t in range(n_frames):
        p, c = person_cutout({"image": a["image"][t], "mask": a["mask"][t]}, crop=box)
        img, m = place(bg, p, c, 0.8, 0.35 + 0.01 * t, 0.95)
        frames.append(img)
        truth.append(m)
    tracker = PersonTracker(models)
    masks, times = [], []
    for f in frames:
        t0 = time.perf_counter()
        res = tracker(f)
        times.append((time.perf_counter() - t0) * 1e3)
        masks.append(torch.zeros(SIZE) if res is None else res.mask)
    ious = [iou(m, t) for m, t in zip(masks, truth, strict=True)]
    return ious, flip_rate(masks), flip_rate(truth), times[1:]  # frame 0 is a photo-style search


def astronaut(models) -> float:
    from skimage import data

    img = torch.from_numpy(data.astronaut()).permute(2, 0, 1).float() / 255
    m = segment_person(img, models).mask
    person = ((225, 120), (230, 60), (150, 400), (250, 330), (100, 480), (300, 450))
    bg = ((20, 100), (480, 20), (400, 200), (330, 60), (60, 20), (470, 300))
    return (sum(int(m[y, x] == 1) for x, y in person) + sum(int(m[y, x] == 0) for x, y in bg)) / 12


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--people", type=int, default=8)
    ap.add_argument("--frames", type=int, default=30)
    args = ap.parse_args()
    torch.set_num_threads(2)
    models = PersonModels(threads=2)
    rows, photo_ms = photos(models, args.people)
    ious = [r[3] for r in rows]
    print(table(["person", "background", "height", "IoU"], [list(r) for r in rows]))
    clip_iou, flips, true_flips, frame_ms = clip(models, args.frames)
    print()
    print(table(["set", "n", "IoU mean", "IoU median", "IoU min", "ms per 720p frame (median, 2 threads)"], [
        ["photos: generated people over real photos", len(ious), float(np.mean(ious)), float(np.median(ious)),
         float(np.min(ious)), statistics.median(photo_ms)],
        ["video: tracked frames", len(clip_iou), float(np.mean(clip_iou)), float(np.median(clip_iou)),
         float(np.min(clip_iou)), statistics.median(frame_ms)],
    ]))
    print(f"\nflip rate per frame: tracked {flips:.4f}, true masks {true_flips:.4f} "
          f"(ratio {flips / true_flips:.2f}; bound 1.5)")
    print(f"astronaut: {astronaut(models):.0%} of 12 hand-picked person/background points right")
    weights = Path(__file__).resolve().parents[1] / "relightnet" / "weights"
    size = sum(f.stat().st_size for f in weights.glob("*.onnx"))
    print(f"shipped ONNX files: {size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
