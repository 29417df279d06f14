"""The ``segment`` job: person masks (and landmarks) of a photo, a folder of photos or a video, written out.

:func:`segment_files` is what ``relightnet segment`` runs: a photo gives a PNG mask, a folder of
photos a folder of masks (``NAME.png``), a video a mask video (``.mkv`` lossless, ``.mp4``) or a
folder of frame masks (``frame_00000.png``, ...); with ``landmarks`` the 33 body landmarks of
every photo or frame are saved too. Masks are white on black. A folder of masks is written into a
hidden folder beside it and moved in only when every mask is made, so a failed run leaves none.
"""

from __future__ import annotations

import contextlib
import logging
import shutil
import tempfile
from pathlib import Path

import torch

from ..checks import InputError
from ..io.probe import PHOTO_SUFFIXES
from .steady import STEADY_MARGIN

__all__ = ["MASK_VIDEO_SUFFIXES", "segment_files", "save_landmarks"]

logger = logging.getLogger("relightnet.segment")

#: Mask videos the job writes.
MASK_VIDEO_SUFFIXES = (".mp4", ".mkv")


def _mask_rgb(mask: torch.Tensor) -> torch.Tensor:
    """(H, W) {0, 1} -> (H, W, 3) uint8 white-on-black."""
    return (mask > 0.5).to(torch.uint8).mul(255)[..., None].expand(-1, -1, 3).contiguous()


@contextlib.contextmanager
def _folder_out(out: Path):
    """A hidden folder beside ``out`` whose files move into ``out`` only when the block succeeds."""
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: is a file; expected a folder (made if needed)")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        yield tmp
        out.mkdir(exist_ok=True)
        for f in sorted(tmp.iterdir()):
            f.replace(out / f.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def save_landmarks(path, results: list, names: list[str] | None = None) -> None:
    """Write the landmarks of T photos or frames (atomically) as ``.npz``: ``landmarks`` (T, 33, 5)
    x, y in pixels, z, visibility, presence; ``world`` (T, 33, 3) metres; ``score``, ``found`` (T,);
    ``names`` (33,); ``files`` (T,) with ``names``. A frame without a person (None) is NaN, not found."""
    import numpy as np

    from ..io import atomic_write
    from .models import LANDMARK_NAMES

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


def _photos(paths: list[Path], out: Path, models, allow_empty: bool, soft: bool = False) -> list:
    from ..io import read_image, write_image
    from .matte import soft_matte
    from .person import segment_person

    results = []
    single = len(paths) == 1 and out.suffix.lower() == ".png"
    with contextlib.nullcontext(out) if single else _folder_out(out) as dest:
        for p in paths:
            img = read_image(p).permute(2, 0, 1)
            try:
                res = segment_person(img, models, name=str(p))
            except InputError:
                if not allow_empty:
                    raise
                logger.warning("%s: no person found: empty mask", p)
                res = None
            results.append(res)
            mask = torch.zeros(img.shape[1:]) if res is None else res.mask
            # --soft: the segmentation's probability refined on the photo in the border band, 8-bit gray.
            pixels = soft_matte(img, res.probability)[..., None] if soft and res is not None else _mask_rgb(mask)
            write_image(dest if single else dest / f"{Path(p).stem}.png", pixels, srgb=False)
    return results


def _video(video: Path, out: Path, models, allow_empty: bool, smoothing: float, progress: bool,
           steady: float) -> list:
    from tqdm import tqdm

    from ..io import VideoWriter, count_frames, read_video, video_info, write_image
    from .video import track_person

    info = video_info(video)
    frames = (torch.from_numpy(f).permute(2, 0, 1).float() / 255 for f in read_video(video))
    tracked = track_person(frames, models, smoothing, allow_empty=allow_empty, name=str(video), steady=steady)
    results, empty = [], []
    as_video = out.suffix.lower() in MASK_VIDEO_SUFFIXES
    with VideoWriter(out, fps=info.fps) if as_video else _folder_out(out) as dest:
        for t, (img, res) in enumerate(tqdm(tracked, total=count_frames(video) or None, desc="segment", unit="frame",
                                            disable=not progress)):
            results.append(res)
            if res is None:
                empty.append(t)
            mask = _mask_rgb(torch.zeros(img.shape[1:]) if res is None else res.mask)
            if as_video:
                dest.write(mask.numpy())
            else:
                write_image(dest / f"frame_{t:05d}.png", mask, srgb=False)
        if not results:
            raise InputError(f"{video}: the video has no frames")
        if len(empty) == len(results):
            raise InputError(f"{video}: no person found in any frame")
    if empty:
        logger.warning("%s: no person in %d frame(s) (first: frame %d): their masks are empty", video, len(empty),
                       empty[0])
    return results


def segment_files(src, out, models, landmarks=None, allow_empty: bool = False, smoothing: float = 0.5,
                  progress: bool = True, steady: float = STEADY_MARGIN, soft: bool = False) -> list:
    """Segment a photo, a folder of photos or a video and write the masks (module docstring).

    Args:
        src: a photo (PNG/JPEG), a folder of photos or a video.
        out: a ``.png`` (a photo), a folder (photos or a video), or a mask video (a video).
        models: the :class:`~relightnet.segment.PersonModels`.
        landmarks: also write the landmarks to this ``.npz`` (:func:`save_landmarks`), or None.
        allow_empty: photos/frames without a person get an empty mask instead of an error.
        smoothing: video: weight of the new frame in the tracked crop (1: none).
        progress: show a tqdm bar over a video's frames.
        steady: video: hysteresis margin of the temporal mask filter (:mod:`relightnet.segment.steady`; 0: off).
        soft: photos: write the soft matte (:func:`~relightnet.segment.matte.soft_matte` of the
            segmentation's probability; an 8-bit gray PNG) instead of the binary mask.

    Returns:
        The :class:`~relightnet.segment.PersonMask` (or None) of each photo or frame.

    Raises:
        InputError: an output of the wrong kind for the input, no photos, no person (without
            ``allow_empty``), a video without frames.
    """
    src, out = Path(src), Path(out)
    names = None
    if src.is_dir():
        files = sorted(f for f in src.iterdir() if f.is_file() and not f.name.startswith("."))
        paths = [f for f in files if f.suffix.lower() in PHOTO_SUFFIXES]
        if not paths:
            raise InputError(f"{src}: no photos ({', '.join(PHOTO_SUFFIXES)}) in the folder")
        if len(paths) < len(files):
            logger.warning("%s: %d file(s) that are not photos skipped (%s)", src, len(files) - len(paths),
                           ", ".join(f.name for f in files if f not in paths)[:200])
        if out.suffix:
            raise InputError(f"--out {out}: a folder of photos gives a folder of masks; expected a folder path")
        results, names = _photos(paths, out, models, allow_empty, soft), [p.name for p in paths]
    elif src.suffix.lower() in PHOTO_SUFFIXES:
        if out.suffix.lower() != ".png":
            raise InputError(f"--out {out}: expected a .png path for the mask of a photo")
        results = _photos([src], out, models, allow_empty=False, soft=soft)
    else:
        if soft:
            raise InputError(f"--soft: {src}: the soft matte is written for photos; expected a photo or a folder "
                             "of photos")
        if out.suffix and out.suffix.lower() not in MASK_VIDEO_SUFFIXES:
            raise InputError(f"--out {out}: expected a mask video (.mkv lossless, .mp4) or a folder for a video")
        results = _video(src, out, models, allow_empty, smoothing, progress, steady)
    if landmarks is not None:
        save_landmarks(landmarks, results, names)
    return results
