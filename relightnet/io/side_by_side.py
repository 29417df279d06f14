"""Videos played side by side in one video (a demo's source | result)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

from .video import VideoWriter, read_video

__all__ = ["write_side_by_side"]


def write_side_by_side(out, videos, fps: float) -> Path:
    """Write the frames of ``videos`` side by side, left to right, each scaled to the first one's
    height (area averaging down, bilinear up; widths rounded to even), for as many frames as the
    shortest has. Written atomically (:class:`VideoWriter`).

    Args:
        out: the video to write. videos: paths of the videos to place, in order. fps: frame rate.

    Returns:
        ``out`` as a Path.
    """
    with VideoWriter(out, fps=fps) as v:
        for frames in zip(*(read_video(p) for p in videos), strict=False):
            h = frames[0].shape[0]
            v.write(np.concatenate([_to_height(f, h) for f in frames], axis=1))
    return Path(out)


def _to_height(frame: np.ndarray, h: int) -> np.ndarray:
    """(H, W, 3) uint8 → (h, W·h/H rounded to even, 3) uint8."""
    if frame.shape[0] == h:
        return frame
    w = max(2, 2 * round(frame.shape[1] * h / frame.shape[0] / 2))
    x = torch.from_numpy(frame).permute(2, 0, 1)[None].float()
    y = F.interpolate(x, size=(h, w), mode="area" if h < frame.shape[0] else "bilinear")
    return y[0].permute(1, 2, 0).round().clamp(0, 255).to(torch.uint8).numpy()
