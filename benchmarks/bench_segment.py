"""Person segmentation: IoU on generated people over real photographs and on scikit-image's
astronaut, flip rate on a clip, and milliseconds per 720p frame on 2 threads.

Run: ``.venv/bin/python benchmarks/bench_segment.py [--people 8] [--frames 30] [--photos DIR]``.

Scenes: people made by the package's generator (Anny bodies with painted clothes, 512², train
split) composited at random sizes (50-92% of the frame height) and places into 1280 x 720
versions of scikit-image's real photographs (coffee, rocket, chelsea, motorcycle, brick; not camera, which shows a man);
the true mask is the composited coverage above one half. The clip: a generated person
walking while drifting right 13 px a frame over the coffee photo. The astronaut has no
true mask: it is reported by the share of its hand-picked person / background points that
come out right. Timing: photos (both stages: candidates + 2 refinements) and tracked video
frames (one pose-model read), medians.

``--photos DIR`` adds a real-pixel stand-in for real footage: each photo of a person in DIR is
filmed by a moving camera (slow pan and zoom with hand-held shake: sub-pixel translation and
rotation noise), 720 px high. The reference masks are the photo's own segmentation (at the
photo's size) carried by the same camera motion: a mask that moves exactly with the picture,
so every flip beyond the reference's is the tracker's own flicker. The person does not move
(no limbs crossing, no motion blur): it measures flicker on real appearance, not on real motion.
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


def _camera(t: int, rng: np.random.Generator) -> torch.Tensor:
    """(2, 3) affine_grid matrix of frame t: pan 0.3% of the width and zoom 0.25% a frame, shake."""
    s = 1.0 / (1.0 + 0.0025 * t)
    a = np.deg2rad(rng.normal(0.0, 0.15))
    dx, dy = 0.003 * t + rng.normal(0.0, 0.002), rng.normal(0.0, 0.002)
    return torch.tensor([[s * np.cos(a), -s * np.sin(a), dx], [s * np.sin(a), s * np.cos(a), dy]],
                        dtype=torch.float32)


def real_footage(models, path: Path, n_frames: int, seed: int = 0):
    """(IoU per frame, flip rate tracked, flip rate of the reference) for one photo filmed by
    a moving camera (module docstring)."""
    import torch.nn.functional as F

    from relightnet.io import read_image

    photo = read_image(path).permute(2, 0, 1)
    ref = segment_person(photo, models).mask
    h = 720
    w = round(photo.shape[2] * h / photo.shape[1] / 2) * 2
    rng = np.random.default_rng(seed)
    tracker = PersonTracker(models)
    masks, truth = [], []
    for t in range(n_frames):
        grid = F.affine_grid(_camera(t, rng)[None], [1, 3, h, w], align_corners=False)
        frame = F.grid_sample(photo[None], grid, mode="bilinear", padding_mode="border", align_corners=False)[0]
        true = F.grid_sample(ref[None, None], grid, mode="bilinear", align_corners=False)[0, 0] > 0.5
        res = tracker(frame.clamp(0, 1))
        masks.append(torch.zeros(h, w) if res is None else res.mask)
        truth.append(true.float())
    ious = [iou(m, t) for m, t in zip(masks, truth, strict=True)]
    return ious, flip_rate(masks), flip_rate(truth)


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
    ap.add_argument("--photos", type=Path, default=None, help="folder of real photos of people (module docstring)")
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
          f"(ratio {flips / true_flips:.2f}; bound 1.2)")
    if args.photos is not None:
        real_rows = []
        for p in sorted(args.photos.glob("*.jp*g")) + sorted(args.photos.glob("*.png")):
            r_iou, r_flips, r_true = real_footage(models, p, args.frames)
            real_rows.append([p.name[:24], float(np.mean(r_iou)), float(np.min(r_iou)), r_flips, r_true,
                              r_flips / r_true])
        print()
        print(table(["real photo, moving camera", "IoU mean", "IoU min", "flips tracked", "flips reference",
                     "ratio (bound 1.5)"], real_rows))
    print(f"astronaut: {astronaut(models):.0%} of 12 hand-picked person/background points right")
    weights = Path(__file__).resolve().parents[1] / "relightnet" / "weights"
    size = sum(f.stat().st_size for f in weights.glob("*.onnx"))
    print(f"shipped ONNX files: {size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
