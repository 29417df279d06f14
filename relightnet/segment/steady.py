"""Steady person masks over time: the previous frame's mask, carried along the person's motion,
decides the pixels that the current frame leaves uncertain.

A tracked mask's outline shimmers: from one frame to the next the pose model reads a slightly
different crop, and the outline's pixels, whose probability is near one half, flip. A running
average of the masks would hold them, but it lags whatever moves. Here, for frame t:

1. **Motion** (:func:`landmark_motion`): the scale (per axis: a person turning gets narrower, not
   shorter) and shift that carry frame t − 1's landmarks onto frame t's, by least squares over
   the landmarks seen in both.
2. **Carry** (:func:`carry_mask`): frame t − 1's steady mask moved by that motion onto frame t's
   pixels (nearest pixel).
3. **Hysteresis** (:func:`hysteresis`): within ``REACH`` pixels of the carried outline, a pixel
   the carried mask calls person stays person unless its probability falls below 0.5 − margin,
   and a background pixel becomes person only above 0.5 + margin. A confident pixel (a moving
   arm: the probability near 0 or 1) follows the current frame at once, and so does an outline
   that moved farther than ``REACH`` beyond what the landmarks' motion explains (a limb moving
   on its own): only the band of uncertain probabilities near the carried outline keeps its
   previous state, so a moving part is held back by at most that band. The largest region is kept.

With the frames themselves (:func:`flow_carry`), the previous mask is carried along the optical
flow instead (:mod:`.flow`, computed in the crop's window at :data:`FLOW_SIDE` pixels): the flow
follows what the landmarks cannot — hair, a skirt, a hand — and where it is reliable the carried
mask also enters the probability (weight :data:`MASK_CARRY`) before the hysteresis; where it is not
(an occlusion, motion blur, a fast turn) the landmarks' motion carries the mask as above.

The first frame, and a person found again after being lost, has no history: its mask is the
probability above one half, as in a photo.
"""

from __future__ import annotations

import numpy as np
import torch

from ..checks import InputError, check_shape

__all__ = ["STEADY_MARGIN", "FLOW_SIDE", "MASK_CARRY", "landmark_motion", "carry_mask", "flow_carry", "near_outline",
           "hysteresis"]

#: The default hysteresis margin on the probability (0: no temporal filtering).
STEADY_MARGIN = 0.15
#: A landmark takes part in the motion when its visibility and presence both exceed this.
MIN_VISIBILITY = 0.5
#: The motion's scale is kept within [1 / MAX_SCALE, MAX_SCALE] (a frame-to-frame zoom).
MAX_SCALE = 1.25
#: The previous state is kept only this many pixels (at most) from the carried outline (:func:`hysteresis`).
REACH = 6
#: The masks' flow is computed on the crop's window scaled to at most this many pixels a side.
FLOW_SIDE = 256
#: The weight of the flow-carried previous mask in the probability where the flow is fully reliable.
MASK_CARRY = 0.5


def landmark_motion(prev: torch.Tensor, cur: torch.Tensor, min_visibility: float = MIN_VISIBILITY,
                    ) -> tuple[float, float, float, float] | None:
    """The scale per axis and shift (sx, sy, tx, ty) taking ``prev``'s landmarks onto ``cur``'s.

    Least squares of ``x_cur ≈ sx · x_prev + tx`` and ``y_cur ≈ sy · y_prev + ty`` over the
    landmarks whose visibility and presence exceed ``min_visibility`` in both; each scale is
    clamped to [1 / MAX_SCALE, MAX_SCALE].

    Args:
        prev, cur: (33, 5) landmarks (x, y in pixels, z, visibility, presence), or (N, ≥ 5).

    Returns:
        (sx, sy, tx, ty), or None when fewer than 3 landmarks are seen in both frames.
    """
    check_shape(prev, ["N", "C"], name="prev landmarks")
    check_shape(cur, [prev.shape[0], prev.shape[1]], name="cur landmarks")
    if prev.shape[1] < 5:
        raise InputError(f"landmarks: expected (N, 5) x, y, z, visibility, presence, got {tuple(prev.shape)}")
    prev, cur = prev.detach().double().numpy(), cur.detach().double().numpy()  # numpy: tiny arrays, no thread pool
    seen = (prev[:, 3:5].min(1) > min_visibility) & (cur[:, 3:5].min(1) > min_visibility)
    if int(seen.sum()) < 3:
        return None
    p, c = prev[seen, :2], cur[seen, :2]
    pm, cm = p.mean(0), c.mean(0)
    var = ((p - pm) ** 2).sum(0)
    s = np.where(var > 1e-9, ((p - pm) * (c - cm)).sum(0) / np.maximum(var, 1e-9), 1.0)
    s = s.clip(1.0 / MAX_SCALE, MAX_SCALE)
    t = cm - s * pm
    return float(s[0]), float(s[1]), float(t[0]), float(t[1])


def carry_mask(mask: torch.Tensor, motion: tuple[float, float, float, float],
               window: tuple[int, int, int, int] | None = None) -> torch.Tensor:
    """Move a (H, W) mask by ``motion`` (sx, sy, tx, ty): out(x, y) = mask((x − tx) / sx, (y − ty) / sy),
    nearest pixel, background outside.

    Args:
        mask: (H, W) mask (person above 0.5; e.g. the previous frame's).
        motion: (sx, sy, tx, ty), shifts in pixels (:func:`landmark_motion`).
        window: (x0, y0, x1, y1) pixels of the output to compute (the rest is background); None: all.

    Returns:
        (H, W) bool.
    """
    H, W = check_shape(mask, ["H", "W"], name="mask").values()
    sx, sy, tx, ty = motion
    x0, y0, x1, y1 = window if window is not None else (0, 0, W, H)
    out = np.zeros((H, W), bool)
    if x1 > x0 and y1 > y0:  # pixel i covers [i, i + 1): its centre i + 0.5 reads the pixel under (i + 0.5 - t) / s
        xs = np.floor((np.arange(x0, x1) + 0.5 - tx) / sx).astype(np.int64)
        ys = np.floor((np.arange(y0, y1) + 0.5 - ty) / sy).astype(np.int64)
        inside = (ys[:, None] >= 0) & (ys[:, None] < H) & (xs[None, :] >= 0) & (xs[None, :] < W)
        src = mask.numpy() > 0.5
        out[y0:y1, x0:x1] = src[np.ix_(ys.clip(0, H - 1), xs.clip(0, W - 1))] & inside
    return torch.from_numpy(out)


def flow_carry(previous: np.ndarray, current: np.ndarray, mask: torch.Tensor, window: tuple[int, int, int, int],
               side: int = FLOW_SIDE) -> tuple[np.ndarray, np.ndarray]:
    """The previous frame's mask carried along the optical flow into a window of the current frame.

    Args:
        previous, current: (H, W) uint8 gray frames (:func:`~relightnet.segment.flow.gray_u8`).
        mask: (H, W) the previous frame's mask.
        window: (x0, y0, x1, y1) pixels of the current frame to carry into.
        side: the flow is computed on the window scaled to at most this many pixels a side.

    Returns:
        ``(carried (h, w) float32 in [0, 1], reliability (h, w) float32)`` over the window.
    """
    import cv2

    from .flow import backward_flow, warp_back

    x0, y0, x1, y1 = window
    h, w = y1 - y0, x1 - x0
    scale = min(1.0, side / max(h, w))
    size = (max(8, round(w * scale)), max(8, round(h * scale)))
    a, b = (cv2.resize(f[y0:y1, x0:x1], size, interpolation=cv2.INTER_AREA) for f in (previous, current))
    flow = backward_flow(a, b)
    fx = cv2.resize(flow.flow[..., 0], (w, h), interpolation=cv2.INTER_LINEAR) * (w / size[0])
    fy = cv2.resize(flow.flow[..., 1], (w, h), interpolation=cv2.INTER_LINEAR) * (h / size[1])
    rel = cv2.resize(flow.reliability, (w, h), interpolation=cv2.INTER_LINEAR)
    carried = warp_back(mask.numpy().astype(np.float32, copy=False), np.stack([fx, fy], -1), (x0, y0),
                        zero_outside=True)
    return carried.clip(0, 1), rel.clip(0, 1)


def _dilate(a: np.ndarray, reach: int) -> np.ndarray:
    """(H, W) bool: ``a`` dilated by the square of side 2 · reach + 1 (rows, then columns; bool arrays only)."""
    rows = a.copy()
    for s in range(1, reach + 1):
        rows[:, s:] |= a[:, :-s]
        rows[:, :-s] |= a[:, s:]
    out = rows.copy()
    for s in range(1, reach + 1):
        out[s:] |= rows[:-s]
        out[:-s] |= rows[s:]
    return out


def near_outline(mask: torch.Tensor, reach: int) -> torch.Tensor:
    """(H, W) bool: the pixels within ``reach`` pixels (a square) of a (H, W) mask's outline (above 0.5).

    A pixel is near the outline when the square of side 2 · reach + 1 around it holds both person
    and background (outside the frame counts as background): the person dilated by that square,
    and the background dilated by it. Only bool maps are made (a few bytes a pixel at any frame size).
    """
    check_shape(mask, ["H", "W"], name="mask")
    fg = mask.numpy() > 0.5
    if reach <= 0:
        return torch.zeros(fg.shape, dtype=torch.bool)
    fg = np.pad(fg, reach)  # background outside the frame
    near = _dilate(fg, reach)
    near &= _dilate(~fg, reach)
    return torch.from_numpy(np.ascontiguousarray(near[reach:-reach, reach:-reach]))


def hysteresis(probability: torch.Tensor, carried: torch.Tensor | None, margin: float,
               reach: int = REACH) -> torch.Tensor:
    """Person pixels of a (H, W) probability with the carried previous mask's state (module docstring).

    Args:
        probability: (H, W) in [0, 1].
        carried: (H, W) previous mask carried onto this frame (person above 0.5), or None (no history).
        margin: the band half-width around 0.5 in which the previous state is kept (0: none).
        reach: the previous state is kept only within this many pixels of the carried outline;
            farther, the outline has moved more than the carried motion explains (a limb moving on
            its own), and the current frame decides, so a moving part is not dragged.

    Returns:
        (H, W) bool.
    """
    check_shape(probability, ["H", "W"], name="probability")
    p = probability.numpy()  # numpy: whole-map comparisons without torch's thread pool (a busy machine)
    if carried is None or margin <= 0:
        return torch.from_numpy(p > 0.5)
    check_shape(carried, list(probability.shape), name="carried mask")
    was = carried.numpy() > 0.5
    held = np.where(was, p > 0.5 - margin, p > 0.5 + margin)
    return torch.from_numpy(np.where(near_outline(carried, reach).numpy(), held, p > 0.5))
