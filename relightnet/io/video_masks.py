"""Per-frame person masks of a video: a folder of mask images or a mask video, read beside the frames."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from pathlib import Path

import torch

from ..checks import InputError
from .video import VideoInfo, count_frames, read_video, video_info

__all__ = ["read_masks", "frames_with_masks"]


def read_masks(masks) -> tuple[int, Iterator[torch.Tensor]]:
    """Per-frame person masks from a folder of images (sorted by name) or from a mask video.

    An image's alpha is the mask where it has transparency; otherwise white = person (see
    :func:`~relightnet.io.read_mask`).

    Returns:
        (count, iterator of (H, W) float32 masks in {0, 1}); a mask video whose container stores
        no frame count (mkv, webm) is counted by decoding it.
    """
    from .image import read_mask
    from .probe import PHOTO_SUFFIXES

    p = Path(masks)
    if p.is_file() and p.suffix.lower() in PHOTO_SUFFIXES:
        raise InputError(f"{p}: a single image; expected a folder of per-frame mask images or a mask video")
    if p.is_dir():
        files = sorted(f for f in p.iterdir() if f.suffix.lower() in PHOTO_SUFFIXES and not f.name.startswith("."))
        if not files:
            raise InputError(f"{p}: no mask images ({', '.join(PHOTO_SUFFIXES)}) in the folder")
        return len(files), (read_mask(f) for f in files)
    # white = person: the mean of R, G, B above 127, i.e. their sum above 381 (no float copy of the frame)
    return count_frames(p), ((torch.from_numpy(f).sum(-1, dtype=torch.int16) > 381).float() for f in read_video(p))


def frames_with_masks(video, masks, allow_empty: bool = False
                      ) -> tuple[VideoInfo, int, Iterator[tuple[int, torch.Tensor, torch.Tensor]]]:
    """Stream a video's frames with their masks, checking that they belong together.

    Args:
        video: the video file.
        masks: a folder of mask images or a mask video (:func:`read_masks`).
        allow_empty: pass empty masks (frames without the person) on instead of failing.

    Returns:
        (video info, mask count, iterator of (t, frame (3, H, W) float sRGB in [0, 1], mask (H, W))).
        The counts are compared before any frame is decoded (both counted from the packets
        really in the files, :func:`count_frames`); the iterator raises :class:`InputError`
        when a mask's size differs from its frame, a mask is empty (unless ``allow_empty``),
        or a damaged file decodes fewer frames than it holds.
    """
    info = video_info(video)
    n_masks, mask_iter = read_masks(masks)
    n_frames = count_frames(video)
    if n_frames != n_masks:
        raise InputError(f"{masks}: {n_masks} masks for {n_frames} video frames")

    def pairs():
        for t, (frame, mask) in enumerate(itertools.zip_longest(read_video(video), mask_iter)):
            if frame is None or mask is None:
                raise InputError(f"{masks}: {n_masks} masks but the video {video} has a different number of frames")
            img = torch.from_numpy(frame).permute(2, 0, 1).float().div_(255)  # one float copy of the frame
            if tuple(mask.shape) != tuple(img.shape[1:]):
                raise InputError(f"{masks}: mask {t} is {tuple(mask.shape)}, frame is {tuple(img.shape[1:])}")
            if not allow_empty and not mask.any():
                raise InputError(f"{masks}: the mask of frame {t} (counting from 0) is empty")
            yield t, img, mask

    return info, n_masks, pairs()
