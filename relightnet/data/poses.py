"""Random bodies and poses for the synthetic data: phenotypes, presets, motions, perturbations, yaw.

Poses (:func:`sample_pose`): with probability 0.35 a preset of
:data:`relightnet.body.POSE_PRESETS` (``arms_down`` and ``arms_crossed`` most often:
arms at the sides or across the chest occlude the torso), otherwise a procedural motion
(walk, turn, idle, arm raise) at a random time of a clip. On top, random rotations of the
spine, neck, head, shoulders, elbows, wrists, hips, knees and ankles, each within a
per-joint range (a fraction of what the joint allows, :data:`JOINT_RANGES`), scaled by a
per-sample magnitude in [0, 1]; elbows and knees only flex (one-sided ranges).

Body yaw (:func:`sample_yaw`): the person is turned about the vertical axis; frontal views
dominate (60 % within ±35° of facing the camera), then side views, then backs.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from ..body import MOTION_KINDS, PHENOTYPES, make_motion, pose_preset
from ..body.base import compose_rotvecs
from ..checks import InputError

__all__ = ["PRESET_WEIGHTS", "MOTION_WEIGHTS", "JOINT_RANGES", "sample_phenotype", "sample_pose",
           "perturbation", "sample_yaw", "SEQUENCE_FPS"]

#: Preset name → probability (given that a preset is used).
PRESET_WEIGHTS = {"arms_down": 0.35, "arms_crossed": 0.3, "apose": 0.15, "rest": 0.1, "tpose": 0.1}
#: Motion kind → probability (given that a motion is used).
MOTION_WEIGHTS = {"walk": 0.35, "idle": 0.25, "turn": 0.2, "arm_raise": 0.2}
#: Frames per second of the motions (stills pick a random time in a 4 s clip).
SEQUENCE_FPS = 30.0

#: Bone → ((lo, hi) degrees about world x, y, z) at magnitude 1. The body faces +z:
#: x bends the spine/neck forward (+), y turns, z tilts sideways.
JOINT_RANGES: dict[str, tuple[tuple[float, float], ...]] = {
    **{f"spine0{i}": ((-4, 6), (-6, 6), (-4, 4)) for i in range(1, 6)},
    "neck01": ((-10, 15), (-20, 20), (-10, 10)),
    "head": ((-12, 15), (-25, 25), (-10, 10)),
    "upperarm01.L": ((-25, 20), (-10, 10), (-5, 25)),
    "upperarm01.R": ((-25, 20), (-10, 10), (-25, 5)),
    "lowerarm01.L": ((-35, 0), (-5, 5), (-5, 5)),
    "lowerarm01.R": ((-35, 0), (-5, 5), (-5, 5)),
    "wrist.L": ((-25, 25), (-20, 20), (-20, 20)),
    "wrist.R": ((-25, 25), (-20, 20), (-20, 20)),
    "upperleg01.L": ((-15, 8), (-8, 8), (-4, 8)),
    "upperleg01.R": ((-15, 8), (-8, 8), (-8, 4)),
    "lowerleg01.L": ((0, 25), (0, 0), (0, 0)),
    "lowerleg01.R": ((0, 25), (0, 0), (0, 0)),
    "foot.L": ((-10, 10), (0, 0), (-5, 5)),
    "foot.R": ((-10, 10), (0, 0), (-5, 5)),
}


def sample_phenotype(rng: np.random.Generator, ages=(0.6, 1.0)) -> dict[str, float]:
    """Anny phenotype values: any gender, ``ages`` range, varied muscle, weight, height, proportions."""
    out = {
        "gender": rng.uniform(0.0, 1.0),
        "age": rng.uniform(float(ages[0]), float(ages[1])),
        "muscle": rng.beta(1.5, 1.5),
        "weight": rng.beta(1.6, 1.8),
        "height": rng.uniform(0.15, 0.6),
        "proportions": rng.uniform(0.0, 0.7),
    }
    return {k: float(np.clip(v, PHENOTYPES[k][0], PHENOTYPES[k][1])) for k, v in out.items()}


def perturbation(rng: np.random.Generator, magnitude: float) -> dict[str, np.ndarray]:
    """Random per-bone rotation vectors (world axes, radians) within :data:`JOINT_RANGES` × magnitude."""
    out = {}
    for bone, rng3 in JOINT_RANGES.items():
        u = rng.uniform(0.0, 1.0, 3)
        lo = np.radians([r[0] for r in rng3])
        hi = np.radians([r[1] for r in rng3])
        out[bone] = magnitude * (lo + u * (hi - lo))
    return out


def _compose(base: dict[str, torch.Tensor], extra: dict[str, np.ndarray]) -> dict[str, torch.Tensor]:
    """Apply ``extra`` after ``base`` bone by bone (rotation vectors (T, 3) and (3,))."""
    out = dict(base)
    for bone, rv in extra.items():
        r = torch.as_tensor(rv, dtype=torch.float64)
        if bone in out:
            b = out[bone].double()
            out[bone] = compose_rotvecs(b, r.expand_as(b)).float()
        else:
            out[bone] = r[None].float()
    return out


def sample_pose(rng: np.random.Generator, n_frames: int = 1, kind: str | None = None) -> tuple[dict, dict]:
    """A random pose (stills) or motion clip (``n_frames`` > 1) for :class:`~relightnet.body.AnnyBody`.

    Args:
        rng: the random generator.
        n_frames: 1 for a still; T for a clip (always a motion then).
        kind: force a motion kind (default: drawn).

    Returns:
        ``params`` (``{"pose": {bone: (T, 3)}, "trans": (T, 3)}``) and a JSON-serialisable
        description (``type`` preset/motion, ``name``, ``time_s``/``frames``, ``perturbation``).
    """
    use_preset = n_frames == 1 and kind is None and rng.uniform() < 0.35
    preset = list(PRESET_WEIGHTS)[int(rng.choice(len(PRESET_WEIGHTS), p=list(PRESET_WEIGHTS.values())))]
    drawn = list(MOTION_WEIGHTS)[int(rng.choice(len(MOTION_WEIGHTS), p=list(MOTION_WEIGHTS.values())))]
    kind = drawn if kind is None else kind
    if kind not in MOTION_KINDS:
        raise InputError(f"motion kind: expected one of {MOTION_KINDS}, got {kind!r}")
    t0 = float(rng.uniform(0.0, 4.0))
    mseed = int(rng.integers(2**31 - 1))
    magnitude = float(rng.uniform(0.0, 1.0)) if n_frames == 1 else float(rng.uniform(0.0, 0.5))
    extra = perturbation(rng, magnitude)
    if use_preset:
        base = {b: torch.tensor(v, dtype=torch.float32)[None] for b, v in pose_preset(preset).items()}
        trans = torch.zeros(1, 3)
        desc = {"type": "preset", "name": preset}
    else:
        start = int(round(t0 * SEQUENCE_FPS)) if n_frames == 1 else 0
        m = make_motion(kind, start + n_frames, fps=SEQUENCE_FPS, seed=mseed)
        base = {b: v[start:] for b, v in m["pose"].items()}
        trans = m["trans"][start:]
        desc = {"type": "motion", "name": kind, "seed": mseed, "fps": SEQUENCE_FPS}
        desc.update({"time_s": start / SEQUENCE_FPS} if n_frames == 1 else {"frames": n_frames})
    desc["perturbation"] = magnitude
    return {"pose": _compose(base, extra), "trans": trans}, desc


def sample_yaw(rng: np.random.Generator) -> float:
    """Body yaw in radians (0 = facing the camera): 60 % frontal, 28 % side, 12 % back."""
    r = rng.uniform()
    a = rng.uniform(-1.0, 1.0)
    if r < 0.6:
        return math.radians(35) * a
    if r < 0.88:
        return math.copysign(math.radians(35 + 100 * abs(a)), a)
    return math.pi + math.radians(45) * a
