"""How good a fit is, against the truth where it is known (generated clips).

All 3D errors are in millimetres over the mapped landmarks (:attr:`AnnyLandmarks.mapped`):
MPJPE after aligning the hip midpoints, PA-MPJPE after the best similarity transform per
frame, acceleration error (second differences, mm/frame²), foot skating (horizontal motion
of a heel or toe that stays on the ground, mm/frame).
"""

from __future__ import annotations

import torch

from ..checks import check_shape
from .init import kabsch
from .terms import HIP_SLOTS

__all__ = ["mpjpe", "pa_mpjpe", "acceleration_error", "foot_skating", "mask_iou", "landmark_error"]


def _root_aligned(x: torch.Tensor) -> torch.Tensor:
    a, b = HIP_SLOTS
    return x - 0.5 * (x[:, a:a + 1] + x[:, b:b + 1])


def mpjpe(pred: torch.Tensor, true: torch.Tensor, mapped: torch.Tensor) -> torch.Tensor:
    """(T,) mean per-joint position error in mm after aligning the hip midpoints.

    Args:
        pred, true: (T, 33, 3) metres; mapped: (33,) bool.
    """
    d = check_shape(pred, ["T", 33, 3], name="pred")
    check_shape(true, [d["T"], 33, 3], name="true")
    return (_root_aligned(pred) - _root_aligned(true))[:, mapped].norm(dim=-1).mean(1) * 1000


def pa_mpjpe(pred: torch.Tensor, true: torch.Tensor, mapped: torch.Tensor) -> torch.Tensor:
    """(T,) MPJPE in mm after the best rotation, scale and translation per frame (Procrustes)."""
    check_shape(pred, ["T", 33, 3], name="pred")
    p, q = pred[:, mapped].double(), true[:, mapped].double()
    pc, qc = p - p.mean(1, keepdim=True), q - q.mean(1, keepdim=True)
    R = kabsch(pc, qc, torch.ones(pc.shape[:2], dtype=pc.dtype))
    rp = pc @ R.transpose(1, 2)
    s = (rp * qc).sum((1, 2)) / rp.square().sum((1, 2)).clamp_min(1e-12)
    return (s[:, None, None] * rp - qc).norm(dim=-1).mean(1).float() * 1000


def acceleration_error(pred: torch.Tensor, true: torch.Tensor, mapped: torch.Tensor) -> torch.Tensor:
    """(T − 2,) mean difference of second differences (mm/frame²), after aligning the hip midpoints.

    Root alignment removes the global path so that the term measures the body's jitter (as the
    HMR / VIBE papers compute it).
    """
    a = _root_aligned(pred)[:, mapped]
    b = _root_aligned(true)[:, mapped]
    acc = lambda x: x[2:] - 2 * x[1:-1] + x[:-2]  # noqa: E731
    return (acc(a) - acc(b)).norm(dim=-1).mean(1) * 1000


def foot_skating(points: torch.Tensor, slots=(29, 30, 31, 32), contact: float = 0.03) -> float:
    """Mean horizontal motion (mm/frame) of foot points that are within ``contact`` metres of the
    clip's lowest foot height in both frames of a step (y up, world frame; 0 when none is)."""
    check_shape(points, ["T", 33, 3], name="points")
    f = points[:, list(slots)].double()
    ground = f[..., 1].min()
    on = f[..., 1] < ground + contact
    both = on[1:] & on[:-1]
    if not bool(both.any()):
        return 0.0
    step = (f[1:, :, [0, 2]] - f[:-1, :, [0, 2]]).norm(dim=-1)
    return float(step[both].mean()) * 1000


def mask_iou(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """(T,) intersection over union of (T, H, W) masks (> 0.5); 1 where both are empty."""
    a, b = a > 0.5, b > 0.5
    inter = (a & b).flatten(1).sum(1).double()
    union = (a | b).flatten(1).sum(1).double()
    return torch.where(union > 0, inter / union.clamp_min(1), torch.ones_like(union))


def landmark_error(pixels: torch.Tensor, true_pixels: torch.Tensor, mapped: torch.Tensor,
                   height: torch.Tensor) -> torch.Tensor:
    """(T,) median 2D landmark error as a percentage of the person's height in pixels (T,)."""
    e = (pixels - true_pixels)[:, mapped].norm(dim=-1)
    return e.median(dim=1).values / height * 100
