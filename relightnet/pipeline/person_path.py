"""Where the target's person stands in every frame, and the avatar's path that follows them.

``avatar --replace-person`` puts the avatar in the person's place frame by frame:

1. **Track.** Every frame's mask gives the person's feet (the mean column of the mask's lowest
   rows, the bottom row) and height in pixels (:func:`relightnet.pipeline.clean_plate.person_box`);
   frames with an empty mask have none.
2. **Smooth, robustly.** A value the frame's edges cut (a person entering or leaving) is missing,
   and so is a box whose height strays far from its neighbours' (:data:`OUTLIER_SHARE`).
   Each of the three tracks is filled across missing frames (linear interpolation), passed through
   a running median of :data:`MEDIAN_WINDOW` frames (a frame where the segmentation lost a foot or
   merged a shadow is an outlier, not a step) and then through the least-squares Hermite smoother
   of :mod:`relightnet.temporal` (knots every :data:`KNOT_SPACING` frames), so the avatar glides
   with the person instead of jittering with the masks; before the first and after the last value
   the feet go on at the track's speed there (:func:`smooth_track`).
3. **Place.** The camera stays where the median frame puts it
   (:func:`relightnet.pipeline.clean_plate.placed_camera`: the default orientation, so the light stays
   camera-relative); in frame t the avatar's root moves to the point seen at the person's feet at the
   depth at which the avatar's standing height spans the person's height in pixels
   (:func:`path_offsets`), so a person walking across the frame, or toward the camera, is followed.

Shapes: T frames; a track is (T, 3) (feet u, feet v, height; pixels).
"""

from __future__ import annotations

import math

import numpy as np
import torch

from ..checks import InputError, check_shape

__all__ = ["MEDIAN_WINDOW", "KNOT_SPACING", "OUTLIER_SHARE", "OUTLIER_WINDOW", "smooth_track", "path_offsets"]

#: Frames of the running median that rejects outlying boxes.
MEDIAN_WINDOW = 7
#: Frames between the Hermite smoother's knots.
KNOT_SPACING = 8.0
#: A box whose height strays by more than this share from the median height of the boxes within
#: ±OUTLIER_WINDOW frames is no box (a person's height in the frame does not jump by a fifth in half a second).
OUTLIER_SHARE = 0.2
OUTLIER_WINDOW = 15


def _fill(x: np.ndarray) -> np.ndarray:
    """(T,) with NaNs replaced by linear interpolation between known values (the nearest at the ends)."""
    known = np.flatnonzero(~np.isnan(x))
    return np.interp(np.arange(len(x)), known, x[known])


def _running_median(x: np.ndarray, r: int) -> np.ndarray:
    """(T,) median over a window of ±r frames, narrowed symmetrically at the ends (a straight track stays one)."""
    n = len(x)
    return np.array([np.median(x[t - w:t + w + 1]) for t in range(n) for w in [min(r, t, n - 1 - t)]])


def _smooth_span(x: np.ndarray) -> np.ndarray:
    """(n,) running median then the Hermite smoother, of a track without gaps."""
    from ..temporal.smoothers import smoothing_matrix

    med = _running_median(x, MEDIAN_WINDOW // 2)
    if len(x) < 4:  # too short for a spline: the median alone
        return med
    return smoothing_matrix(len(x), "hermite", knot_spacing=min(KNOT_SPACING, (len(x) - 1) / 2)).numpy() @ med


def _outliers(h: np.ndarray) -> np.ndarray:
    """(T,) bool frames whose height differs by more than :data:`OUTLIER_SHARE` from the median of the known
    heights within ±:data:`OUTLIER_WINDOW` frames (a stray blob the segmentation took for the person)."""
    out = np.zeros(len(h), dtype=bool)
    for t in np.flatnonzero(~np.isnan(h)):
        near = h[max(0, t - OUTLIER_WINDOW):t + OUTLIER_WINDOW + 1]
        med = np.median(near[~np.isnan(near)])
        out[t] = abs(h[t] - med) > OUTLIER_SHARE * med
    return out


def smooth_track(boxes: list, fallback) -> np.ndarray:
    """(T, 3) smoothed (feet u, feet v, height) from per-frame boxes, as in the module docstring.

    Args:
        boxes: per frame a 3-tuple (NaN where the frame's edges cut a value) or None (no person).
        fallback: (3,) the value of a track missing in every frame (the median placement's).

    Returns:
        (T, 3): each track smoothed over the frames from its first to its last value (gaps between filled
        linearly); before and after, the feet continue in a straight line at the speed of the first / last
        half-second of the smoothed track (a person entering or leaving the frame) and the height is held.
    """
    if len(boxes) == 0:
        raise InputError("person track: no frames")
    x = np.array([[math.nan] * 3 if b is None else list(b) for b in boxes], dtype=np.float64)
    T = len(x)
    x[_outliers(x[:, 2])] = math.nan
    out = np.empty_like(x)
    for k in range(3):
        known = np.flatnonzero(~np.isnan(x[:, k]))
        if len(known) == 0:
            out[:, k] = float(fallback[k])
            continue
        i0, i1 = int(known[0]), int(known[-1])
        s = _smooth_span(_fill(x[i0:i1 + 1, k]))
        out[i0:i1 + 1, k] = s
        m = min(len(s) - 1, 15)
        v0, v1 = ((s[m] - s[0]) / m, (s[-1] - s[-1 - m]) / m) if m > 0 and k < 2 else (0.0, 0.0)
        out[:i0, k] = s[0] - v0 * (i0 - np.arange(i0))
        out[i1 + 1:, k] = s[-1] + v1 * np.arange(1, T - i1)
    return out


def path_offsets(size, placement, track: np.ndarray, body_height: float,
                 fov_deg: float = 35.0) -> torch.Tensor:
    """(T, 3) world offsets (metres) of the avatar's root from the origin, so that with the camera of
    :func:`~relightnet.pipeline.clean_plate.placed_camera` (``size`` (H, W), ``placement`` the median
    :class:`~relightnet.pipeline.clean_plate.Placement`)
    a body of ``body_height`` metres standing at the offset has its feet at ``track[t, :2]`` and spans
    ``track[t, 2]`` pixels (pinhole, the camera looking along −z)."""
    check_shape(torch.as_tensor(track), ["T", 3], name="track")
    if not (np.all(track[:, 2] > 0) and placement.height > 0 and body_height > 0):
        raise InputError("person track: expected positive heights")
    H, W = int(size[0]), int(size[1])
    f = (H / 2) / math.tan(math.radians(fov_deg) / 2)
    d_med = f * body_height / placement.height  # the camera's distance from the origin
    d = f * body_height / track[:, 2]  # each frame's depth in front of the camera
    # A point at view depth d seen at pixel (u, v), relative to the camera: ((u − W/2) d/f, −(v − H/2) d/f, −d).
    eye_rel = np.stack([(W / 2 - placement.feet[0]) * d_med / f, (placement.feet[1] - H / 2) * d_med / f, d_med])
    pts = np.stack([(track[:, 0] - W / 2) * d / f, -(track[:, 1] - H / 2) * d / f, -d], 1)
    return torch.as_tensor(eye_rel[None] + pts, dtype=torch.float32)
