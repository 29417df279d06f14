"""``relightnet segment``: person masks (and body landmarks) of a photo, a folder of photos or a video."""

from __future__ import annotations

import argparse
import contextlib
import logging
import shutil
import tempfile
from pathlib import Path

from .common import add_command, in_path, nonneg_int, out_dir, out_file

logger = logging.getLogger("relightnet.segment")

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
VIDEO_OUT = (".mp4", ".mkv")


def _mask_rgb(mask):
    """(H, W) {0, 1} -> (H, W, 3) uint8 white-on-black."""
    import torch

    return (mask > 0.5).to(torch.uint8).mul(255)[..., None].expand(-1, -1, 3).contiguous()


@contextlib.contextmanager
def _folder_out(out: Path):
    """A hidden folder beside ``out`` whose files move into ``out`` only when the block succeeds."""
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: --out is a file; expected a folder (made if needed)")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        yield tmp
        out.mkdir(exist_ok=True)
        for f in sorted(tmp.iterdir()):
            f.replace(out / f.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _save_landmarks(path, results, names=None) -> None:
    import numpy as np

    from ..io import atomic_write
    from ..segment.models import LANDMARK_NAMES

    found = np.array([r is not None for r in results])
    lm = np.full((len(results), len(LANDMARK_NAMES), 5), np.nan, np.float32)
    world = np.full((len(results), len(LANDMARK_NAMES), 3), np.nan, np.float32)
    score = np.zeros(len(results), np.float32)
    for t, r in enumerate(results):
        if r is not None:
            lm[t], world[t], score[t] = r.landmarks.numpy(), r.world.numpy(), r.score
    extra = {} if names is None else {"files": np.array(names)}
    with atomic_write(path) as f:
        np.savez(f, landmarks=lm, world=world, score=score, found=found, names=np.array(LANDMARK_NAMES), **extra)
    logger.info("wrote %s (%d frame(s), landmarks (T, 33, 5), world (T, 33, 3))", path, len(results))


def _photos(paths, out: Path, models, allow_empty: bool):
    import torch

    from ..io import read_image, write_image
    from ..segment import segment_person

    results = []
    single = len(paths) == 1 and out.suffix.lower() == ".png"
    with contextlib.nullcontext(out) if single else _folder_out(out) as dest:
        for p in paths:
            img = read_image(p).permute(2, 0, 1)
            try:
                res = segment_person(img, models, name=str(p))
            except ValueError:
                if not allow_empty:
                    raise
                logger.warning("%s: no person found: empty mask", p)
                res = None
            results.append(res)
            mask = torch.zeros(img.shape[1:]) if res is None else res.mask
            write_image(dest if single else dest / f"{Path(p).stem}.png", _mask_rgb(mask), srgb=False)
    return results


def _video(video: Path, out: Path, models, allow_empty: bool, smoothing: float):
    import torch
    from tqdm import tqdm

    from ..io import VideoWriter, read_video, video_info, write_image
    from ..segment import track_person

    info = video_info(video)
    frames = (torch.from_numpy(f).permute(2, 0, 1).float() / 255 for f in read_video(video))
    tracked = track_person(frames, models, smoothing, allow_empty=allow_empty, name=str(video))
    results, empty = [], []
    as_video = out.suffix.lower() in VIDEO_OUT
    with VideoWriter(out, fps=info.fps) if as_video else _folder_out(out) as dest:
        for t, (img, res) in enumerate(tqdm(tracked, total=info.n_frames or None, desc="segment", unit="frame",
                                            disable=not logger.isEnabledFor(logging.INFO))):
            results.append(res)
            if res is None:
                empty.append(t)
            mask = _mask_rgb(torch.zeros(img.shape[1:]) if res is None else res.mask)
            if as_video:
                dest.write(mask.numpy())
            else:
                write_image(dest / f"frame_{t:05d}.png", mask, srgb=False)
        if not results:
            raise ValueError(f"{video}: the video has no frames")
        if len(empty) == len(results):
            raise ValueError(f"{video}: no person found in any frame")
    if empty:
        logger.warning("%s: no person in %d frame(s) (first: frame %d): their masks are empty", video, len(empty),
                       empty[0])
    return results


def run(args: argparse.Namespace) -> int:
    from ..segment import PersonModels

    src = in_path(args.input, "INPUT", "a photo, a folder of photos or a video")
    out = out_file(args.out) if Path(args.out).suffix else out_dir(args.out)
    if args.landmarks:
        out_file(args.landmarks, "--landmarks", (".npz",))
    models = PersonModels(threads=args.threads)
    names = None
    if src.is_dir():
        paths = sorted(f for f in src.iterdir() if f.suffix.lower() in IMAGE_SUFFIXES)
        if not paths:
            raise ValueError(f"{src}: no photos (.png/.jpg) in the folder")
        if out.suffix:
            raise ValueError(f"--out {out}: a folder of photos gives a folder of masks; expected a folder path")
        results, names = _photos(paths, out, models, args.allow_empty), [p.name for p in paths]
    elif src.suffix.lower() in IMAGE_SUFFIXES:
        if out.suffix.lower() != ".png":
            raise ValueError(f"--out {out}: expected a .png path for the mask of a photo")
        results = _photos([src], out, models, allow_empty=False)
    else:
        if out.suffix and out.suffix.lower() not in VIDEO_OUT:
            raise ValueError(f"--out {out}: expected a mask video (.mkv lossless, .mp4) or a folder for a video")
        results = _video(src, out, models, args.allow_empty, args.smoothing)
    if args.landmarks:
        _save_landmarks(args.landmarks, results, names)
    logger.info("wrote %s", out)
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "segment",
        "Person masks from the shipped segmentation models (MediaPipe, Apache-2.0, in ONNX Runtime): a photo "
        "gives a PNG mask, a folder of photos a folder of masks, a video a mask video (or a folder of frame "
        "masks; the person is tracked from frame to frame). The largest person is taken.",
        "  relightnet segment person.jpg --out person_mask.png\n"
        "  relightnet segment photos/ --out masks/ --landmarks landmarks.npz\n"
        "  relightnet segment clip.mp4 --out clip_masks.mkv            # lossless mask video, one mask per frame\n"
        "  relightnet segment clip.mp4 --out masks/ --allow-empty     # frame_00000.png, ...\n",
    )
    p.add_argument("input", help="a photo (PNG/JPEG), a folder of photos or a video")
    p.add_argument("--out", required=True, help="mask PNG (photo), folder (photos or video) or mask video .mkv/.mp4")
    p.add_argument("--landmarks", metavar="FILE.npz",
                   help="also save the 33 body landmarks per photo/frame: landmarks (T, 33, 5) x, y in pixels, "
                   "z, visibility, presence; world (T, 33, 3) metres; score, found (T,); names (33,)")
    p.add_argument("--allow-empty", action="store_true",
                   help="photos/frames without a person get an empty mask (default: an error naming them)")
    p.add_argument("--smoothing", type=float, default=0.5,
                   help="video: weight of the new frame in the tracked crop (1: no smoothing; default: 0.5)")
    p.add_argument("--threads", type=nonneg_int, default=0, help="ONNX Runtime threads (default: 0, all cores)")
    p.set_defaults(func=run)
