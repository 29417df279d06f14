"""Anny motion files: what ``relightnet fit`` writes and ``render-body``/``avatar --motion`` read.

Format (``.npz``; world frame: y up, the ground at y = 0, bodies of ``ground="rest"``):

- ``body_model``: the string ``"anny"``;
- ``pose`` (T, J, 3) float32: rotation vectors of Anny's J = 104 bones in world axes
  (:class:`relightnet.body.AnnyBody`'s ``pose``; bone 0 the global orientation);
- ``bone_names`` (J,): the bone names, in order (checked against the body);
- ``trans`` (T, 3) float32, metres; ``phenotype`` (6,) float32 in
  :data:`relightnet.body.PHENOTYPES` order; ``fps``;
- optional: ``camera_view`` (4, 4) world → the source camera's view, ``camera_intrinsics``
  (4,) ``(fx, fy, cx, cy)``, ``camera_size`` (2,) (H, W); ``residual_2d`` (T,) the fit's RMS
  landmark error as a fraction of the person's height; ``interpolated`` (T,) bool, frames
  where no person was found.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, ShapeError
from ..io.arrays import read_npz, read_npz_names
from ..io.atomic import atomic_write
from .anny_model import PHENOTYPES

__all__ = ["AnnyMotion", "is_anny_motion", "load_anny_motion", "save_anny_motion"]

_EXTRA = {"camera_view": (4, 4), "camera_intrinsics": (4,), "camera_size": (2,)}


@dataclass(frozen=True, eq=False)
class AnnyMotion:
    """An Anny motion clip (see the module docstring for the fields; tensors float32)."""

    pose: torch.Tensor
    trans: torch.Tensor
    phenotype: torch.Tensor
    bone_names: tuple[str, ...]
    fps: float = 30.0
    extra: dict[str, torch.Tensor] = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return self.pose.shape[0]

    def body_params(self) -> dict[str, torch.Tensor]:
        """Parameters for :class:`relightnet.body.AnnyBody`: pose (T, J, 3), trans (T, 3), phenotype (1, 6)."""
        return {"pose": self.pose, "trans": self.trans, "phenotype": self.phenotype[None]}


def is_anny_motion(path: str | Path) -> bool:
    """Whether an ``.npz`` file says it is an Anny motion (has ``body_model``)."""
    path = Path(path)
    if path.suffix != ".npz" or not path.is_file():
        return False
    return "body_model" in read_npz_names(path)


def _array(raw: dict, key: str, fname: str, shape: tuple, what: str) -> np.ndarray:
    if key not in raw:
        raise InputError(f"{fname}: missing key {key!r} (an Anny motion file needs {what})")
    try:
        a = np.asarray(raw[key], dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{fname}: key {key!r}: not a numeric array") from None
    if a.shape != shape:
        want = "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
        raise ShapeError(f"{fname}: key {key!r}: expected {want}, got {tuple(a.shape)}")
    if not np.isfinite(a).all():
        raise InputError(f"{fname}: key {key!r}: contains NaN or Inf values")
    return a


def _validated(raw: dict, fname: str, bone_names=None) -> AnnyMotion:
    kind = str(np.asarray(raw.get("body_model", "")).reshape(-1)[0]) if "body_model" in raw else None
    if kind != "anny":
        hint = " (an SMPL motion drives --body smpl:MODEL)" if "poses" in raw else ""
        raise InputError(f"{fname}: key 'body_model': expected 'anny', got {kind!r}{hint}")
    pose = np.asarray(raw.get("pose", np.zeros((0,))))
    if pose.ndim != 3 or pose.shape[0] < 1 or pose.shape[2] != 3:
        raise ShapeError(f"{fname}: key 'pose': expected (T, J, 3), got {tuple(pose.shape)}")
    T, J = pose.shape[:2]
    pose = _array(raw, "pose", fname, (T, J, 3), "pose (T, J, 3)")
    names = tuple(str(n) for n in np.asarray(raw.get("bone_names", [])).reshape(-1))
    if len(names) != J or (bone_names is not None and tuple(bone_names) != names):
        n = J if bone_names is None else len(bone_names)
        raise InputError(f"{fname}: key 'bone_names': expected the body's {n} bone names in order, "
                         f"got {len(names)} names")
    trans = _array(raw, "trans", fname, (T, 3), "trans (T, 3)")
    phen = _array(raw, "phenotype", fname, (len(PHENOTYPES),), "phenotype (6,)")
    for j, (n, (lo, hi, _)) in enumerate(PHENOTYPES.items()):
        if not lo - 1e-6 <= phen[j] <= hi + 1e-6:
            raise InputError(f"{fname}: key 'phenotype': {n} = {phen[j]:.3g} is outside [{lo:.3g}, {hi:.3g}]")
    fps = float(_array(raw, "fps", fname, (), "fps")) if "fps" in raw else 30.0
    if fps <= 0:
        raise InputError(f"{fname}: key 'fps': expected a positive number, got {fps}")
    extra = {k: torch.as_tensor(_array(raw, k, fname, s, str(s)), dtype=torch.float32) for k, s in _EXTRA.items()
             if k in raw}
    for k in ("residual_2d", "interpolated"):
        if k in raw:
            extra[k] = torch.as_tensor(_array(raw, k, fname, (T,), f"{k} (T,)"), dtype=torch.float32)
    f32 = torch.float32
    return AnnyMotion(torch.as_tensor(pose, dtype=f32), torch.as_tensor(trans, dtype=f32),
                      torch.as_tensor(phen, dtype=f32), names, fps, extra)


def load_anny_motion(path: str | Path, bone_names=None) -> AnnyMotion:
    """Read an Anny motion file; ``bone_names`` (the body's) are checked when given.

    Raises:
        InputError / ShapeError: one line naming the file and the key.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such motion file")
    if path.suffix != ".npz":
        raise InputError(f"{path.name}: expected an .npz Anny motion file")
    return _validated(read_npz(path, "motion file"), path.name, bone_names)


def save_anny_motion(path: str | Path, motion: AnnyMotion) -> Path:
    """Write ``motion`` as ``.npz`` (atomically)."""
    path = Path(path)
    if path.suffix != ".npz":
        raise InputError(f"{path.name}: expected an .npz motion file")
    arrays = {"body_model": np.array("anny"), "pose": motion.pose.detach().cpu().numpy().astype(np.float32),
              "bone_names": np.array(list(motion.bone_names)),
              "trans": motion.trans.detach().cpu().numpy().astype(np.float32),
              "phenotype": motion.phenotype.detach().cpu().numpy().astype(np.float32),
              "fps": np.float32(motion.fps)}
    arrays.update({k: v.detach().cpu().numpy() for k, v in motion.extra.items()})
    _validated(arrays, path.name)
    with atomic_write(path) as f:
        np.savez(f, **arrays)
    return path
