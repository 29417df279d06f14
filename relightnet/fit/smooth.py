"""The final smoothing pass of a video fit, and the fit's placement in a world frame (both a block of frames at a time).

:func:`smooth_motion` smooths rotations as matrices (a Gaussian-weighted mean over
neighbouring frames, projected back onto rotations: no wrap-around at 180° as rotation
vectors would have) and translations with the same weights; frames near the ends use the
weights that fall inside the clip. :func:`place_in_world` turns the camera-space track into
an Anny motion in a world frame: y up along the body's mean up axis, the lowest foot point
of the clip on y = 0, the first frame's pelvis above the origin.
"""

from __future__ import annotations

import math
from dataclasses import replace

import torch

from ..body.anny_motion import AnnyMotion
from ..body.base import matrix_to_rotvec, rotvec_to_matrix
from ..checks import InputError, check_shape
from .body_model import FitBody
from .solve import FitResult

__all__ = ["SMOOTH_BLOCK", "gaussian_weights", "smooth_rotations", "smooth_motion", "place_in_world", "FOOT_SLOTS"]

#: Heels and toes among the 33 landmarks (the points that touch the ground).
FOOT_SLOTS = (29, 30, 31, 32)


#: Frames smoothed at once: the Gaussian's weights are a band (±3 σ), applied a block of output frames at a
#: time, so smoothing a long video holds a few MB, not a (T, T) matrix (0.8 GB at 10,000 frames). A clip
#: of at most this many frames is one block: the (T, T) weights of :func:`gaussian_weights`.
SMOOTH_BLOCK = 256


def _band_weights(a: int, b: int, n: int, sigma: float) -> tuple[torch.Tensor, int, int]:
    """(b − a, hi − lo) rows [a, b) of :func:`gaussian_weights` (n, sigma > 0) over the columns [lo, hi)
    outside which they are 0, and lo, hi."""
    k = math.ceil(3 * sigma)
    lo, hi = (0, n) if (a, b) == (0, n) else (max(0, a - k), min(n, b + k))
    t = torch.arange(n, dtype=torch.float64)
    d = t[a:b, None] - t[None, lo:hi]
    w = torch.exp(-0.5 * (d / sigma) ** 2)
    w = torch.where(d.abs() <= 3 * sigma, w, torch.zeros_like(w))
    return w / w.sum(1, keepdim=True), lo, hi


def gaussian_weights(n: int, sigma: float) -> torch.Tensor:
    """(n, n) row-normalised Gaussian weights over frames (rows: output frames), 0 beyond 3 σ."""
    if sigma < 0:
        raise InputError(f"sigma: expected >= 0 frames, got {sigma}")
    if sigma == 0:
        return torch.eye(n, dtype=torch.float64)
    return _band_weights(0, n, n, sigma)[0]


def smooth_rotations(R: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """(T, ..., 3, 3) rotations → the (N, ..., 3, 3) nearest rotations to their weighted means ((N, T) weights)."""
    T = R.shape[0]
    check_shape(weights, ["N", T], name="weights")
    M = torch.einsum("ts,s...->t...", weights.to(R.dtype), R)
    U, _, Vh = torch.linalg.svd(M)
    s = torch.sign(torch.linalg.det(U @ Vh))
    D = torch.ones(*s.shape, 3, dtype=R.dtype)
    D[..., 2] = s
    return U @ (D[..., None] * Vh)


def smooth_motion(result: FitResult, sigma: float = 1.5) -> FitResult:
    """The fit with its pose and translation smoothed over frames (Gaussian, ``sigma`` frames), a block of
    :data:`SMOOTH_BLOCK` frames at a time."""
    T = result.pose.shape[0]
    if sigma < 0:
        raise InputError(f"sigma: expected >= 0 frames, got {sigma}")
    if T < 3 or sigma == 0:
        return result
    poses, transs = [], []
    for a in range(0, T, SMOOTH_BLOCK):
        b = min(a + SMOOTH_BLOCK, T)
        w, lo, hi = _band_weights(a, b, T, sigma) if (a, b) != (0, T) else (gaussian_weights(T, sigma), 0, T)
        R = rotvec_to_matrix(result.pose[lo:hi].double())
        poses.append(matrix_to_rotvec(smooth_rotations(R, w)).to(result.pose.dtype))
        transs.append((w @ result.trans[lo:hi].double()).to(result.trans.dtype))
    return replace(result, pose=torch.cat(poses), trans=torch.cat(transs))


def _up_rotation(up: torch.Tensor) -> torch.Tensor:
    """(3, 3) the smallest rotation taking unit vector ``up`` to +y."""
    y = up.new_tensor([0.0, 1.0, 0.0])
    v = torch.linalg.cross(up, y)
    s, c = v.norm(), torch.dot(up, y)
    if float(s) < 1e-9:
        return torch.eye(3, dtype=up.dtype) if float(c) > 0 else torch.diag(up.new_tensor([1.0, -1.0, -1.0]))
    return rotvec_to_matrix(v / s * torch.atan2(s, c))


def place_in_world(result: FitResult, fb: FitBody, fps: float = 30.0) -> AnnyMotion:
    """An :class:`~relightnet.body.AnnyMotion` in a world frame (module docstring) with the source camera.

    The body rotates about its pelvis q (the zero-pose pelvis at zero translation), so a world
    rotation R maps orientation G to R·G and translation t to R (q + t) − q (then shifted).
    """
    sub, trans = result.pose.double(), result.trans.double()
    G = rotvec_to_matrix(sub[:, 0])
    up = G[:, :, 1].mean(0)
    R = _up_rotation(up / up.norm())
    base = fb.body.phenotype_tensor(result.phenotype[None])
    with torch.no_grad():
        rest = fb.rest(base)
        q = fb.body(pose=torch.zeros(1, fb.num_joints, 3), phenotype=base).joints[0, 0].double()
        new_sub = sub.clone()
        new_sub[:, 0] = matrix_to_rotvec(R @ G)
        new_trans = (q + trans) @ R.T - q
        feet = []  # the lowest foot point of each block of frames (a long video's points are never all held)
        for a in range(0, sub.shape[0], SMOOTH_BLOCK):
            pts, _ = fb.points(new_sub[a:a + SMOOTH_BLOCK].float(), new_trans[a:a + SMOOTH_BLOCK].float(), rest)
            feet.append(float(pts[:, list(FOOT_SLOTS), 1].min()))
            if a == 0:
                hips = 0.5 * (pts[0, 23] + pts[0, 24]).double()
    shift = torch.zeros(3, dtype=torch.float64)
    shift[1] = -min(feet)
    shift[0], shift[2] = -hips[0], -hips[2]
    new_trans = new_trans + shift
    view = torch.eye(4, dtype=torch.float64)
    view[:3, :3] = R.T
    view[:3, 3] = -(R.T @ shift)
    extra = {"camera_view": view.float(), "camera_intrinsics": torch.tensor(result.intrinsics, dtype=torch.float32),
             "camera_size": torch.tensor(result.size, dtype=torch.float32),
             "residual_2d": result.residual_2d.float(), "interpolated": result.interpolated.float()}
    return AnnyMotion(fb.full_pose(new_sub.float()), new_trans.float(), result.phenotype.float(),
                      tuple(fb.body.joint_names), float(fps), extra)
