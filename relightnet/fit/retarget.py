"""Retarget a fitted motion to the avatar's body: same skeleton, the path scaled, feet kept put.

The rotations carry over as they are (Anny to Anny). The root's horizontal path (relative to
the first frame) is scaled by the ratio of the two bodies' leg lengths (hip to ankle at rest),
the clip's lowest foot point is put on the ground (y = 0), and a foot that stands on the
ground from one frame to the next is held in place: the root is moved by the opposite of the
mean horizontal slide of the heel and toe points within ``contact`` of the ground in both frames.
"""

from __future__ import annotations

from dataclasses import replace

import torch

from ..body.anny_motion import AnnyMotion
from .body_model import FitBody
from .smooth import FOOT_SLOTS

__all__ = ["leg_length", "retarget_motion", "to_default_avatar"]

_HIP_ANKLE = ((23, 27), (24, 28))


def _points(fb: FitBody, pose: torch.Tensor, trans: torch.Tensor, phenotype: torch.Tensor) -> torch.Tensor:
    with torch.no_grad():
        return fb.points(pose[:, fb.bone_index], trans, fb.rest(phenotype[None]))[0]


def leg_length(fb: FitBody, phenotype: torch.Tensor) -> float:
    """Mean hip-to-ankle distance (metres) of the rest body of a (6,) phenotype."""
    pts = _points(fb, torch.zeros(1, fb.num_joints, 3), torch.zeros(1, 3), phenotype)[0]
    return float(sum((pts[a] - pts[b]).norm() for a, b in _HIP_ANKLE) / 2)


def _lock_feet(fb, pose, trans, phenotype, contact: float) -> torch.Tensor:
    trans = trans.clone()
    feet = _points(fb, pose, trans, phenotype)[:, list(FOOT_SLOTS)]  # (T, 4, 3) heels and toes
    on = feet[..., 1] < float(feet[..., 1].min()) + contact
    offset = torch.zeros(3)
    for t in range(1, trans.shape[0]):
        both = on[t] & on[t - 1]
        if bool(both.any()):  # the points standing in both frames slide by this much on average: undo it
            slide = (feet[t, both] - feet[t - 1, both]).mean(0)
            offset[0] -= float(slide[0])
            offset[2] -= float(slide[2])
        trans[t] += offset
    return trans


def retarget_motion(motion: AnnyMotion, fb: FitBody, phenotype: torch.Tensor | None = None,
                    lock_feet: bool = True, contact: float = 0.03) -> AnnyMotion:
    """The motion performed by a body of ``phenotype`` (6,) (default: the motion's own).

    Returns:
        An :class:`~relightnet.body.AnnyMotion` on the ground (y = 0 at the lowest foot point).
    """
    target = motion.phenotype if phenotype is None else phenotype.to(motion.phenotype)
    scale = leg_length(fb, target) / leg_length(fb, motion.phenotype)
    trans = motion.trans.clone()
    trans[:, [0, 2]] = trans[:1, [0, 2]] + scale * (trans[:, [0, 2]] - trans[:1, [0, 2]])
    if lock_feet:
        trans = _lock_feet(fb, motion.pose, trans, target, contact)
    pts = _points(fb, motion.pose, trans, target)
    trans[:, 1] -= float(pts[:, list(FOOT_SLOTS), 1].min())
    return replace(motion, trans=trans, phenotype=target.clone())


def to_default_avatar(motion: AnnyMotion, fb: FitBody) -> AnnyMotion:
    """:func:`retarget_motion` to the default avatar: Anny of the default phenotype, feet held."""
    from ..body import PHENOTYPES

    return retarget_motion(motion, fb, torch.tensor([v[2] for v in PHENOTYPES.values()]))
