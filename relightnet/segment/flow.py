"""Optical flow between two frames, how far to trust it, and sampling a map along it.

The flow is OpenCV's DIS (dense inverse search; Kroeger et al., ECCV 2016) on the frames' gray
levels, run both ways: :func:`backward_flow` gives, for every pixel of the current frame, where
it was in the previous one, with a reliability in [0, 1] from the forward-backward check (a pixel
carried back and forth by the two flows should land where it started; where the two disagree —
an occlusion, a disocclusion, motion blur — it is not trusted) and from the colour constancy of
the pixel along its flow. :func:`warp_back` (numpy) and :func:`sample_along` (torch maps at any
positions) read a map of the previous frame at those places.
What the video jobs carry along it: the CNN's maps (:mod:`relightnet.pipeline.steady_maps`).

Conventions: images are (3, H, W) float sRGB in [0, 1], (H, W) float gray in [0, 1] or (H, W) uint8; a flow is (H, W, 2)
float32 (x, y) in pixels of the frames it was computed on.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import torch
import torch.nn.functional as F

from ..checks import InputError, check_shape

__all__ = ["FLOW_TOLERANCE", "COLOUR_TOLERANCE", "Flow", "gray_u8", "backward_flow", "warp_back", "sample_along"]

#: Forward-backward disagreement (pixels of the flow's frames) at which a pixel's reliability falls to
#: e^-1 ≈ 0.37: half a pixel plus 5% of the motion (a fast motion is measured less exactly).
FLOW_TOLERANCE = 0.5
#: Gray-level change along the flow (0–1) at which the reliability falls to e^-1: a few sensor noise levels.
COLOUR_TOLERANCE = 0.04


class Flow(NamedTuple):
    """What :func:`backward_flow` returns.

    Attributes:
        flow: (H, W, 2) float32: pixel (x, y) of the current frame was at (x, y) + flow in the previous one.
        reliability: (H, W) float32 in [0, 1].
    """

    flow: np.ndarray
    reliability: np.ndarray


def gray_u8(image) -> np.ndarray:
    """(H, W) uint8 gray levels: of a (3, H, W) float sRGB image in [0, 1] (Rec. 601 weights), of an
    (H, W) float gray image in [0, 1], or an (H, W) uint8 array itself."""
    x = torch.as_tensor(image)
    if x.dtype == torch.uint8 and x.ndim == 2:
        return np.ascontiguousarray(x.numpy())
    if x.ndim != 3:
        check_shape(x, ["H", "W"], name="frame")
        return (x.clamp(0, 1) * 255).round().to(torch.uint8).numpy()
    h = check_shape(x, [3, "H", "W"], name="frame")["H"]
    out = np.empty(tuple(x.shape[1:]), np.uint8)
    for r in range(0, h, 256):  # bands of rows: a frame at the pixel limit takes no frame-sized float copy
        b = x[:, r:r + 256]
        g = (0.299 * b[0]).add_(b[1], alpha=0.587).add_(b[2], alpha=0.114)
        out[r:r + 256] = g.clamp_(0, 1).mul_(255).round_().to(torch.uint8).numpy()
    return out


def _dis():
    import cv2

    return cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)


def warp_back(x: np.ndarray, flow: np.ndarray, origin: tuple[int, int] = (0, 0), zero_outside: bool = False
              ) -> np.ndarray:
    """The previous frame's ``x`` read where each pixel of the current one was: bilinear samples of
    (H', W'[, C]) float32 ``x`` at ``origin`` + pixel + ``flow`` for every pixel of an (h, w, 2) flow
    (``origin`` (x0, y0): where the flow's pixel (0, 0) is in ``x``'s frame). Outside ``x``: its border
    repeated, or 0 with ``zero_outside``. Returns (h, w[, C]) float32."""
    import cv2

    h, w = flow.shape[:2]
    gx, gy = np.meshgrid(np.arange(w, dtype=np.float32) + origin[0], np.arange(h, dtype=np.float32) + origin[1])
    border = cv2.BORDER_CONSTANT if zero_outside else cv2.BORDER_REPLICATE
    return cv2.remap(x, gx + flow[..., 0], gy + flow[..., 1], cv2.INTER_LINEAR, borderMode=border, borderValue=0.0)


def backward_flow(previous, current, tolerance: float = FLOW_TOLERANCE,
                  colour_tolerance: float = COLOUR_TOLERANCE) -> Flow:
    """Where each pixel of ``current`` was in ``previous``, and how far to trust it (module docstring).

    Args:
        previous, current: two frames of the same size (:func:`gray_u8`'s inputs).
        tolerance: the forward-backward disagreement (pixels, plus 5% of the motion) for a reliability of e^-1.
        colour_tolerance: the gray-level change along the flow (0–1) for a reliability of e^-1.

    Returns:
        :class:`Flow` ``(flow (H, W, 2), reliability (H, W))``.
    """
    a, b = gray_u8(previous), gray_u8(current)
    if a.shape != b.shape:
        raise InputError(f"flow: the frames differ in size: {a.shape} and {b.shape}")
    if min(a.shape) < 8:
        raise InputError(f"flow: expected frames of at least 8×8 pixels, got {a.shape}")
    if not (tolerance > 0 and colour_tolerance > 0):
        raise InputError(f"flow tolerances: expected positive numbers, got {tolerance!r}, {colour_tolerance!r}")
    dis = _dis()
    back = dis.calc(b, a, None)  # current → previous
    fwd = dis.calc(a, b, None)  # previous → current
    h, w = b.shape
    grid = np.stack(np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32)), -1)
    there = grid + back
    round_trip = back + warp_back(fwd, back)  # ≈ 0 where the two flows agree
    disagree = np.linalg.norm(round_trip, axis=-1)
    scale = tolerance + 0.05 * np.linalg.norm(back, axis=-1)
    change = np.abs(warp_back(a.astype(np.float32), back) - b.astype(np.float32)) / 255
    rel = np.exp(-np.square(disagree / scale) - np.square(change / colour_tolerance))
    inside = (there[..., 0] >= 0) & (there[..., 0] <= w - 1) & (there[..., 1] >= 0) & (there[..., 1] <= h - 1)
    return Flow(back, (rel * inside).astype(np.float32))


def sample_along(x: torch.Tensor, positions: torch.Tensor) -> torch.Tensor:
    """Bilinear samples of maps at pixel positions (outside the maps: 0).

    Args:
        x: (B, C, h, w) maps.
        positions: (H, W, 2) (x, y) pixel positions in the maps' frame (pixel centres at integers).

    Returns:
        (B, C, H, W).
    """
    check_shape(x, ["B", "C", "h", "w"], name="maps")
    check_shape(positions, ["H", "W", 2], name="positions")
    h, w = x.shape[-2:]
    g = positions.to(x.dtype)
    norm = torch.stack([(2 * g[..., 0] + 1) / w - 1, (2 * g[..., 1] + 1) / h - 1], -1)
    return F.grid_sample(x, norm[None].expand(x.shape[0], -1, -1, -1), mode="bilinear", padding_mode="zeros",
                         align_corners=False)
