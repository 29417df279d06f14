"""What the fit may move and how far: the fitted bones, their angle limits, the pose prior.

The fit moves the bones the pose presets and motions use (:data:`FIT_BONES`, the root first:
global orientation); every other Anny bone stays at its reference rotation (zero). A bone's
rotation is a rotation vector in world axes applied in its parent's posed frame (so the
directions are body-relative, :mod:`relightnet.body.motion`): x bends forward, y turns, z tilts.

:data:`JOINT_LIMITS` are per-component bounds (degrees) on those rotation vectors — a box,
a simple stand-in for each joint's range of motion, wide enough for the presets
(``tpose``, ``arms_crossed``) and the motions. :func:`limit_penalty` is zero inside the box
and grows quadratically outside; :func:`rest_penalty` pulls every non-root bone toward
zero (Anny's reference pose).
"""

from __future__ import annotations

import math

import torch

from ..checks import check_shape

__all__ = ["FIT_BONES", "JOINT_LIMITS", "limit_bounds", "limit_penalty", "rest_penalty"]

_ARM = {"L": ((-130, 70), (-70, 70), (-60, 130)), "R": ((-130, 70), (-70, 70), (-130, 60))}
_LEG = {"L": ((-125, 40), (-45, 45), (-30, 50)), "R": ((-125, 40), (-45, 45), (-50, 30))}

#: Bone → ((lo, hi) degrees about x, (lo, hi) about y, (lo, hi) about z); ``root`` is free.
JOINT_LIMITS: dict[str, tuple[tuple[float, float], ...] | None] = {
    "root": None,
    "spine03": ((-30, 45), (-35, 35), (-25, 25)),
    "spine01": ((-30, 45), (-35, 35), (-25, 25)),
    "neck01": ((-40, 50), (-60, 60), (-35, 35)),
    "head": ((-40, 45), (-60, 60), (-30, 30)),
    **{f"upperarm01.{s}": _ARM[s] for s in "LR"},
    **{f"lowerarm01.{s}": ((-150, 35), (-75, 75), (-75, 75)) for s in "LR"},
    **{f"wrist.{s}": ((-70, 70), (-60, 60), (-60, 60)) for s in "LR"},
    **{f"upperleg01.{s}": _LEG[s] for s in "LR"},
    **{f"lowerleg01.{s}": ((-5, 150), (-12, 12), (-12, 12)) for s in "LR"},
    **{f"foot.{s}": ((-45, 45), (-20, 20), (-25, 25)) for s in "LR"},
}
#: The bones the fit moves, root first (a tuple of :data:`JOINT_LIMITS`' keys).
FIT_BONES: tuple[str, ...] = tuple(JOINT_LIMITS)


def limit_bounds(dtype=torch.float32) -> tuple[torch.Tensor, torch.Tensor]:
    """(N, 3) lower and upper bounds in radians for :data:`FIT_BONES` (±inf for the root)."""
    lo = torch.full((len(FIT_BONES), 3), -math.inf, dtype=dtype)
    hi = torch.full((len(FIT_BONES), 3), math.inf, dtype=dtype)
    for i, b in enumerate(FIT_BONES):
        lim = JOINT_LIMITS[b]
        if lim is not None:
            lo[i] = torch.tensor([math.radians(a) for a, _ in lim], dtype=dtype)
            hi[i] = torch.tensor([math.radians(b_) for _, b_ in lim], dtype=dtype)
    return lo, hi


def limit_penalty(pose: torch.Tensor, lo: torch.Tensor, hi: torch.Tensor) -> torch.Tensor:
    """Squared excess (radians²) of rotation-vector components beyond their limits, per frame.

    Args:
        pose: (B, N, 3) rotation vectors of :data:`FIT_BONES`.
        lo, hi: (N, 3) from :func:`limit_bounds`.

    Returns:
        (B,) sum of squared excesses.
    """
    d = check_shape(pose, ["B", "N", 3], name="pose")
    check_shape(lo, [d["N"], 3], name="lo")
    excess = torch.relu(lo.to(pose) - pose) + torch.relu(pose - hi.to(pose))
    return excess.nan_to_num(0.0).square().sum(dim=(1, 2))


def rest_penalty(pose: torch.Tensor) -> torch.Tensor:
    """(B,) squared norm (radians²) of the non-root rotations of a (B, N, 3) pose: the pull to rest."""
    check_shape(pose, ["B", "N", 3], name="pose")
    return pose[:, 1:].square().sum(dim=(1, 2))
