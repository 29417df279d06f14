"""Initial global orientation and translation of each frame, from the landmarks alone.

The orientation is the rotation that best aligns the rest body's torso landmarks with
BlazePose's world landmarks (weighted Kabsch); the depth comes from the ratio of the body's
metric size to its size in pixels, and the position from back-projecting the landmarks' centre.
"""

from __future__ import annotations

import torch

from ..body.base import matrix_to_rotvec
from ..checks import check_shape

__all__ = ["TORSO_SLOTS", "CORE_SLOTS", "MAX_TURN_DEG", "kabsch", "initial_orientation", "relative_turn",
           "initial_translation"]

#: Shoulders and hips: the landmarks that fix the torso's orientation.
TORSO_SLOTS = (11, 12, 23, 24)
#: Shoulders, hips, knees and ankles: the landmarks that fix the body's size and position.
CORE_SLOTS = (11, 12, 23, 24, 25, 26, 27, 28)


def kabsch(p: torch.Tensor, q: torch.Tensor, w: torch.Tensor) -> torch.Tensor:
    """(B, 3, 3) rotations R minimising Σ w ‖R (p − p̄) − (q − q̄)‖² (weighted centroids).

    Args:
        p, q: (B, P, 3) point sets; w: (B, P) weights.
    """
    d = check_shape(p, ["B", "P", 3], name="p")
    check_shape(q, [d["B"], d["P"], 3], name="q")
    w = w.clamp_min(0)[..., None] + 1e-9
    pc = p - (w * p).sum(1, keepdim=True) / w.sum(1, keepdim=True)
    qc = q - (w * q).sum(1, keepdim=True) / w.sum(1, keepdim=True)
    M = (w * qc).transpose(1, 2) @ pc  # (B, 3, 3): Σ w q pᵀ
    U, _, Vh = torch.linalg.svd(M.double())
    s = torch.sign(torch.linalg.det(U @ Vh))
    D = torch.diag_embed(torch.stack([torch.ones_like(s), torch.ones_like(s), s], -1))
    return (U @ D @ Vh).to(p.dtype)


def initial_orientation(rest_points: torch.Tensor, world_view: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """(B, 3) root rotation vectors aligning the rest body's torso with the world landmarks.

    Args:
        rest_points: (33, 3) the rest body's landmark points; world_view: (B, 33, 3) in view axes;
        weights: (B, 33).
    """
    s = list(TORSO_SLOTS)
    B = world_view.shape[0]
    R = kabsch(rest_points[s].expand(B, -1, -1), world_view[:, s], weights[:, s])
    return matrix_to_rotvec(R.double()).to(world_view.dtype)


#: A torso turn between two frames larger than this (degrees) is taken for a landmark error (a
#: left/right swap when the person shows a side or the back) and not followed.
MAX_TURN_DEG = 100.0


def relative_turn(world_view: torch.Tensor, weights: torch.Tensor, max_deg: float = MAX_TURN_DEG) -> torch.Tensor:
    """(T − 1, 3, 3) the torso's turn from frame 0 to each later frame, chained frame to frame.

    What a warm start adds to a fitted frame's orientation: the turn the world landmarks show
    since then (relative, so BlazePose's absolute front/back ambiguity does not enter; chained
    over consecutive frames, each a small turn). A step above ``max_deg`` or with a torso
    landmark unseen counts as no turn.

    Args:
        world_view: (T, 33, 3) world landmarks in view axes (frame 0: the reference); weights: (T, 33).
    """
    d = check_shape(world_view, ["T", 33, 3], name="world_view")
    check_shape(weights, [d["T"], 33], name="weights")
    s = list(TORSO_SLOTS)
    w = torch.minimum(weights[:-1, s], weights[1:, s])
    step = kabsch(world_view[:-1, s], world_view[1:, s], w)  # (T − 1, 3, 3): frame t − 1 → t
    cos = ((step.diagonal(dim1=-2, dim2=-1).sum(-1) - 1) / 2).clamp(-1, 1)
    ok = (torch.rad2deg(torch.acos(cos)) <= max_deg) & (w > 0).all(1)
    step = torch.where(ok[:, None, None], step, torch.eye(3, dtype=step.dtype).expand_as(step))
    out, acc = [], torch.eye(3, dtype=step.dtype)
    for R in step:
        acc = R @ acc
        out.append(acc)
    return torch.stack(out)


def initial_translation(points: torch.Tensor, landmarks: torch.Tensor, weights: torch.Tensor,
                        intrinsics) -> torch.Tensor:
    """(B, 3) translations putting the body (posed, at zero translation) where the landmarks are.

    Args:
        points: (B, 33, 3) the body's landmark points at zero translation (view axes).
        landmarks: (B, 33, ≥2) observed pixels; weights: (B, 33).
        intrinsics: ``(fx, fy, cx, cy)``.
    """
    fx, fy, cx, cy = (float(x) for x in intrinsics)
    s = list(CORE_SLOTS)
    w = weights[:, s].clamp_min(0)[..., None] + 1e-6
    p, u = points[:, s], landmarks[:, s, :2]
    c = (w * p).sum(1) / w.sum(1)
    uc = (w * u).sum(1) / w.sum(1)
    s3 = ((w * (p - c[:, None]).square()[..., :2].sum(-1, keepdim=True)).sum(1) / w.sum(1)).sqrt()[:, 0]
    s2 = ((w * (u - uc[:, None]).square().sum(-1, keepdim=True)).sum(1) / w.sum(1)).sqrt()[:, 0]
    depth = (0.5 * (fx + fy) * s3 / s2.clamp_min(1.0)).clamp(0.3, 100.0)
    target = torch.stack([(uc[:, 0] - cx) * depth / fx, -(uc[:, 1] - cy) * depth / fy, -depth], -1)
    return target - c
