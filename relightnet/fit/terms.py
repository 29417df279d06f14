"""The fit's data terms, each (B,) per frame: landmark reprojection, world landmarks, silhouette.

All are dimensionless: image distances are divided by the person's height in pixels
(``scale``), metric ones by :data:`WORLD_UNIT`, so the weights of :class:`relightnet.fit.FitWeights`
compare like with like. Landmark terms are weighted means over landmarks (BlazePose
visibility, :func:`relightnet.fit.landmarks.landmark_weights`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from ..checks import check_shape
from .camera import project_points

__all__ = ["WORLD_UNIT", "HIP_SLOTS", "person_scale", "reprojection_term", "world_term", "SilhouetteTargets",
           "SILHOUETTE_HEIGHT", "WORK_ASPECT", "working_size", "silhouette_targets", "outline_matches",
           "silhouette_term", "acceleration_term"]

#: Metric residuals are measured in this unit (metres): BlazePose's world points are ~5 cm accurate.
WORLD_UNIT = 0.05
#: Indices of the left and right hip among the 33 landmarks (their midpoint is the world origin).
HIP_SLOTS = (23, 24)


def person_scale(landmarks: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """(B,) the person's height in pixels: the vertical extent of the weighted landmarks (≥ 8 px).

    Args:
        landmarks: (B, 33, ≥2) pixel landmarks.
        weights: (B, 33).
    """
    y = landmarks[..., 1]
    ok = weights > 0
    hi = torch.where(ok, y, torch.full_like(y, -1e9)).amax(1)
    lo = torch.where(ok, y, torch.full_like(y, 1e9)).amin(1)
    return ((hi - lo) * 1.1).clamp_min(8.0)


def reprojection_term(points: torch.Tensor, landmarks: torch.Tensor, weights: torch.Tensor, intrinsics,
                      scale: torch.Tensor) -> torch.Tensor:
    """(B,) weighted mean squared 2D landmark error, in units of the person's height.

    Args:
        points: (B, 33, 3) the body's landmark points in view space.
        landmarks: (B, 33, ≥2) observed pixels.
        weights: (B, 33).
        intrinsics: ``(fx, fy, cx, cy)``.
        scale: (B,) person height in pixels.
    """
    d = check_shape(points, ["B", 33, 3], name="points")
    check_shape(weights, [d["B"], 33], name="weights")
    r = (project_points(points, intrinsics) - landmarks[..., :2]) / scale[:, None, None]
    return (weights * r.square().sum(-1)).sum(1) / weights.sum(1).clamp_min(1e-6)


def world_term(points: torch.Tensor, world_view: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """(B,) weighted mean squared error of hip-relative 3D landmarks, in units of :data:`WORLD_UNIT`.

    Args:
        points: (B, 33, 3) the body's landmark points in view space.
        world_view: (B, 33, 3) BlazePose world points in view axes (:func:`relightnet.fit.observe.world_to_view_axes`).
        weights: (B, 33).
    """
    check_shape(points, ["B", 33, 3], name="points")
    a, b = HIP_SLOTS
    rel = points - 0.5 * (points[:, a:a + 1] + points[:, b:b + 1])
    ref = world_view - 0.5 * (world_view[:, a:a + 1] + world_view[:, b:b + 1])
    r = (rel - ref) / WORLD_UNIT
    return (weights * r.square().sum(-1)).sum(1) / weights.sum(1).clamp_min(1e-6)


#: The silhouette term works on masks resampled so the person is about this many pixels tall
#: (never enlarged): the distance transform and its lookups cost little. At 160 px the benchmark's
#: IoU fell by 0.002–0.003 on two of its three clips; at 240 px it does not.
SILHOUETTE_HEIGHT = 240


@dataclass(frozen=True, eq=False)
class SilhouetteTargets:
    """Per-frame silhouette evidence at a working resolution.

    outside: (B, 1, h, w) distance in working pixels to the nearest mask pixel (0 inside the
    mask); outline: (B, M, 2) working-pixel points sampled on the mask's outline; valid: (B,)
    frames with a mask; factor: (x, y) image pixels → working pixels.
    """

    outside: torch.Tensor
    outline: torch.Tensor
    valid: torch.Tensor
    factor: tuple[float, float] = (1.0, 1.0)


#: The working box is at most this many times :data:`SILHOUETTE_HEIGHT` wide: masks wider than that
#: (a person lying across the frame, noise) are resampled further, so that a frame's mask at the
#: working resolution is bounded (:data:`relightnet.fit.masks.MAX_FRAME_BYTES`). A standing or
#: walking person (box at most 4 × as wide as tall) is never affected.
WORK_ASPECT = 4


def working_size(size, rows: float, cols: float, height: int = SILHOUETTE_HEIGHT,
                 finest: float = 1.0) -> tuple[int, int]:
    """(h, w): the working resolution of (H, W) images whose masks' box (over all frames fitted together)
    spans ``rows`` × ``cols`` image pixels (0: no mask): the person about ``height`` pixels tall, the
    box at most :data:`WORK_ASPECT` × ``height`` wide, never finer than the images (or ``finest`` × their size)."""
    H, W = int(size[0]), int(size[1])
    person = float(rows) if rows else float(H)
    r = min(1.0, height / person, finest)
    if cols:
        r = min(r, WORK_ASPECT * height / float(cols))
    return max(1, round(H * r)), max(1, round(W * r))


def _working_masks(masks: torch.Tensor, size, height: int | None) -> tuple[np.ndarray, tuple[float, float]]:
    """(B, h, w) bool masks resampled (area average, then > 0.5) to :func:`working_size` (``height``
    None: the masks are at it already), and the factors (x, y) image pixels → working pixels.
    Frames are resampled one at a time (a window of full-size frames is never copied to float as a whole)."""
    m = masks.detach().cpu()
    mh, mw = m.shape[-2:]
    H, W = (int(size[0]), int(size[1])) if size is not None else (mh, mw)
    on = m if m.dtype == torch.bool else m > 0.5
    if height is None:
        return on.numpy(), (mw / W, mh / H)
    rows, cols = torch.nonzero(on.any(2).any(0)).flatten(), torch.nonzero(on.any(1).any(0)).flatten()
    person = float(rows.max() - rows.min() + 1) * H / mh if len(rows) else 0
    across = float(cols.max() - cols.min() + 1) * W / mw if len(cols) else 0
    h, w = working_size((H, W), person, across, height, mh / H)
    if (h, w) == (mh, mw):
        return on.numpy(), (w / W, h / H)
    out = np.empty((m.shape[0], h, w), np.bool_)
    for i, frame in enumerate(m):
        out[i] = (F.interpolate(frame.float()[None, None], size=(h, w), mode="area")[0, 0] > 0.5).numpy()
    return out, (w / W, h / H)


def silhouette_targets(masks: torch.Tensor, n_outline: int = 256, size=None,
                       height: int | None = SILHOUETTE_HEIGHT) -> SilhouetteTargets:
    """Distance transforms and outline samples of (B, h, w) masks (computed once per frame).

    Args:
        masks: (B, h, w) person masks in [0, 1] of (H, W) images (any resolution with their aspect).
        n_outline: outline points per frame.
        size: (H, W) of the images the landmarks are in (default: the masks' size).
        height: working height of the person in pixels (:data:`SILHOUETTE_HEIGHT`); None: the masks are
            at their working resolution already (:meth:`relightnet.fit.masks.PackedMasks.working`).
    """
    from scipy import ndimage

    d = check_shape(masks, ["B", "h", "w"], name="masks")
    work, factor = _working_masks(masks, size, height)
    outs, lines, valid = [], [], []
    for m in work:
        if not m.any():
            outs.append(np.zeros(m.shape, np.float32))
            lines.append(np.zeros((n_outline, 2), np.float32))
            valid.append(False)
            continue
        outs.append(ndimage.distance_transform_edt(~m).astype(np.float32))
        edge = m & ~ndimage.binary_erosion(m)
        ys, xs = np.nonzero(edge)
        pick = np.linspace(0, len(xs) - 1, n_outline).round().astype(int)
        lines.append(np.stack([xs[pick] + 0.5, ys[pick] + 0.5], 1).astype(np.float32))
        valid.append(True)
    return SilhouetteTargets(torch.from_numpy(np.stack(outs))[:, None], torch.from_numpy(np.stack(lines)),
                             torch.tensor(valid).reshape(d["B"]), factor)


def _working_pixels(pixels: torch.Tensor, targets: SilhouetteTargets) -> torch.Tensor:
    fx, fy = targets.factor
    return pixels * pixels.new_tensor([fx, fy])


def outline_matches(pixels: torch.Tensor, targets: SilhouetteTargets) -> torch.Tensor:
    """(B, M) index of the projected vertex nearest to each outline point (no gradient).

    Args:
        pixels: (B, S, 2) projected body vertices, image pixels.
        targets: :class:`SilhouetteTargets` of the same B frames.
    """
    check_shape(pixels, ["B", "S", 2], name="pixels")
    with torch.no_grad():
        px = _working_pixels(pixels.detach(), targets)
        o = targets.outline.to(px)
        d2 = o.square().sum(-1)[..., None] - 2 * o @ px.transpose(1, 2) + px.square().sum(-1)[:, None]
        return d2.argmin(-1)


def silhouette_term(pixels: torch.Tensor, targets: SilhouetteTargets, scale: torch.Tensor,
                    matches: torch.Tensor | None = None) -> torch.Tensor:
    """(B,) two-sided silhouette disagreement, in units of the person's height.

    The body's projected vertices should lie inside the mask (their distance-transform value,
    squared) and every outline point should have a projected vertex near it (squared distance
    to its match: the nearest vertex, :func:`outline_matches`, a constant of the step as in
    ICP; pass ``matches`` to reuse those of a recent step). Frames without a mask give 0.

    Args:
        pixels: (B, S, 2) projected body vertices (a subset), image pixels.
        targets: :class:`SilhouetteTargets` of the same B frames.
        scale: (B,) person height in image pixels.
        matches: (B, M) vertex index per outline point, or None (computed here).
    """
    d = check_shape(pixels, ["B", "S", 2], name="pixels")
    H, W = targets.outside.shape[-2:]
    px = _working_pixels(pixels, targets)
    grid = torch.stack([px[..., 0] * (2.0 / W) - 1, px[..., 1] * (2.0 / H) - 1], -1)[:, :, None]
    outside = F.grid_sample(targets.outside.to(pixels), grid, align_corners=False, padding_mode="border")
    inside_term = outside[:, 0, :, 0].square().mean(1)
    if matches is None:
        matches = outline_matches(pixels, targets)
    picked = px.gather(1, matches[..., None].expand(-1, -1, 2))
    near = (picked - targets.outline.to(pixels)).square().sum(-1).mean(1)
    e = (inside_term + near) / (scale * targets.factor[1]).square()
    return torch.where(targets.valid.to(pixels.device), e, torch.zeros_like(e)).reshape(d["B"])


def acceleration_term(points: torch.Tensor, before: torch.Tensor | None = None) -> torch.Tensor:
    """(B,) squared second differences of (B, P, 3) points over frames, in units of 1 cm.

    ``before`` (≤ 2, P, 3) are fixed frames preceding the batch (the previous window), so the
    first frames are smoothed against them. Frame t's value is the acceleration centred on t.
    """
    check_shape(points, ["B", "P", 3], name="points")
    x = points if before is None else torch.cat([before.to(points), points])
    k = 0 if before is None else before.shape[0]
    out = points.new_zeros(points.shape[0])
    if x.shape[0] < 3:
        return out
    acc = ((x[2:] - 2 * x[1:-1] + x[:-2]) / 0.01).square().sum(-1).mean(-1)  # centred on frames 1..n-2 of x
    idx = torch.arange(1, x.shape[0] - 1) - k
    keep = idx >= 0
    return out.index_add(0, idx[keep], acc[keep])
