"""The fit's data terms, each (B,) per frame: landmark reprojection, world landmarks, silhouette.

All are dimensionless: image distances are divided by the person's height in pixels
(``scale``), metric ones by :data:`WORLD_UNIT`, so the weights of :class:`relightnet.fit.FitWeights`
compare like with like. Landmark terms are weighted means over landmarks (BlazePose
visibility, :func:`relightnet.fit.landmark_weights`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from ..checks import check_shape
from .camera import project_points

__all__ = ["WORLD_UNIT", "HIP_SLOTS", "person_scale", "reprojection_term", "world_term", "SilhouetteTargets",
           "silhouette_targets", "silhouette_term", "acceleration_term"]

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
        world_view: (B, 33, 3) BlazePose world points in view axes (:func:`relightnet.fit.world_to_view_axes`).
        weights: (B, 33).
    """
    check_shape(points, ["B", 33, 3], name="points")
    a, b = HIP_SLOTS
    rel = points - 0.5 * (points[:, a:a + 1] + points[:, b:b + 1])
    ref = world_view - 0.5 * (world_view[:, a:a + 1] + world_view[:, b:b + 1])
    r = (rel - ref) / WORLD_UNIT
    return (weights * r.square().sum(-1)).sum(1) / weights.sum(1).clamp_min(1e-6)


@dataclass(frozen=True, eq=False)
class SilhouetteTargets:
    """Per-frame silhouette evidence.

    outside: (B, 1, H, W) distance in pixels to the nearest mask pixel (0 inside the mask);
    outline: (B, M, 2) pixel points sampled on the mask's outline; valid: (B,) frames with a mask.
    """

    outside: torch.Tensor
    outline: torch.Tensor
    valid: torch.Tensor


def silhouette_targets(masks: torch.Tensor, n_outline: int = 256) -> SilhouetteTargets:
    """Distance transforms and outline samples of (B, H, W) masks (bool, or above 0.5 is the person;
    computed once per frame, each written into the one (B, 1, H, W) float32 result)."""
    from scipy import ndimage

    d = check_shape(masks, ["B", "H", "W"], name="masks")
    outside = np.zeros((d["B"], 1, d["H"], d["W"]), np.float32)
    lines, valid = [], []
    m_all = masks.detach().cpu().numpy()
    for i, m in enumerate(m_all if m_all.dtype == np.bool_ else m_all > 0.5):
        if not m.any():
            lines.append(np.zeros((n_outline, 2), np.float32))
            valid.append(False)
            continue
        outside[i, 0] = ndimage.distance_transform_edt(~m)
        edge = m & ~ndimage.binary_erosion(m)
        ys, xs = np.nonzero(edge)
        pick = np.linspace(0, len(xs) - 1, n_outline).round().astype(int)
        lines.append(np.stack([xs[pick] + 0.5, ys[pick] + 0.5], 1).astype(np.float32))
        valid.append(True)
    return SilhouetteTargets(torch.from_numpy(outside), torch.from_numpy(np.stack(lines)),
                             torch.tensor(valid).reshape(d["B"]))


def silhouette_term(pixels: torch.Tensor, targets: SilhouetteTargets, scale: torch.Tensor) -> torch.Tensor:
    """(B,) two-sided silhouette disagreement, in units of the person's height.

    The body's projected vertices should lie inside the mask (their distance-transform value,
    squared) and every outline point should have a projected vertex near it (squared distance
    to the nearest one). Frames without a mask give 0.

    Args:
        pixels: (B, S, 2) projected body vertices (a subset).
        targets: :class:`SilhouetteTargets` of the same B frames.
        scale: (B,) person height in pixels.
    """
    d = check_shape(pixels, ["B", "S", 2], name="pixels")
    H, W = targets.outside.shape[-2:]
    grid = torch.stack([pixels[..., 0] * (2.0 / W) - 1, pixels[..., 1] * (2.0 / H) - 1], -1)[:, :, None]
    outside = F.grid_sample(targets.outside.to(pixels), grid, align_corners=False, padding_mode="border")
    inside_term = outside[:, 0, :, 0].square().mean(1)
    near = torch.cdist(targets.outline.to(pixels), pixels).amin(-1).square().mean(1)
    e = (inside_term + near) / scale.square()
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
