"""SMPL-style motion files: ``poses`` (T, 72), ``betas`` (10,), ``trans`` (T, 3).

Format (``.npz``, or ``.pkl`` of a dict of numpy arrays):

- ``poses`` (T, 72): 24 SMPL joints × axis-angle, joint 0 the global orientation;
- ``betas`` (10,): SMPL shape coefficients;
- ``trans`` (T, 3): root translation, metres;
- optional ``fps`` (scalar; ``mocap_framerate`` / ``mocap_frame_rate`` are read too,
  default 30);
- optional camera: keys ``camera_<name>`` (e.g. ``camera_K`` (3, 3), ``camera_R``
  (T, 3, 3), ``camera_t`` (T, 3)) in ``.npz``, or a ``camera`` dict in ``.pkl``; kept as
  a name → tensor mapping without interpretation.

Poses are in the file's frame. SMPL and most y-up datasets match relightnet's world
(y up, facing +z); z-up data (e.g. AMASS) goes through :func:`reorient_motion` with
:data:`Z_UP_TO_Y_UP`.
"""

from __future__ import annotations

import pickle
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, ShapeError, check_shape
from ..io.arrays import read_npz
from ..io.atomic import atomic_write
from ..io.safe_pickle import load_pickle
from .base import matrix_to_rotvec, rotvec_to_matrix

__all__ = ["Motion", "load_motion", "save_motion", "reorient_motion", "Z_UP_TO_Y_UP"]

#: v_y_up = Z_UP_TO_Y_UP @ v_z_up: −90° about x, (x, y, z) → (x, z, −y).
Z_UP_TO_Y_UP = torch.tensor([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

_FPS_KEYS = ("fps", "mocap_framerate", "mocap_frame_rate")


@dataclass(frozen=True)
class Motion:
    """An SMPL motion clip (float32 tensors).

    Attributes:
        poses: (T, 72) axis-angle.
        betas: (10,) shape.
        trans: (T, 3) translation.
        fps: frames per second.
        camera: optional name → tensor mapping (e.g. ``K``, ``R``, ``t``).
    """

    poses: torch.Tensor
    betas: torch.Tensor
    trans: torch.Tensor
    fps: float = 30.0
    camera: dict[str, torch.Tensor] | None = field(default=None)

    @property
    def n_frames(self) -> int:
        return self.poses.shape[0]

    def body_params(self) -> dict[str, torch.Tensor]:
        """Parameters for :class:`relightnet.body.SMPLBody`: pose (T, 24, 3), betas (1, 10), trans (T, 3)."""
        return {"pose": self.poses.reshape(-1, 24, 3), "betas": self.betas[None], "trans": self.trans}


def _fail_shape(fname: str, key: str, expected: str, got) -> ShapeError:
    return ShapeError(f"{fname}: key {key!r}: expected {expected}, got {tuple(got)}")


def _camera_tensor(value, fname: str, key) -> torch.Tensor:
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{fname}: camera {key!r}: not a numeric array") from None
    if not np.isfinite(a).all():
        raise InputError(f"{fname}: camera {key!r}: contains NaN or Inf values")
    return torch.as_tensor(a, dtype=torch.float32)


def _validated(raw: dict, fname: str) -> Motion:
    missing = [k for k in ("poses", "betas", "trans") if k not in raw]
    if missing:
        raise InputError(
            f"{fname}: missing key {missing[0]!r} (a motion file needs 'poses' (T, 72), 'betas' (10,), 'trans' (T, 3))"
        )
    arrs = {}
    for k in ("poses", "betas", "trans"):
        try:
            arrs[k] = np.asarray(raw[k], dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError(f"{fname}: key {k!r}: not a numeric array") from None
    poses, betas, trans = arrs["poses"], arrs["betas"], arrs["trans"]
    if poses.ndim != 2 or poses.shape[1] != 72:
        raise _fail_shape(fname, "poses", "(T, 72)", poses.shape)
    T = poses.shape[0]
    if T < 1:
        raise _fail_shape(fname, "poses", "(T, 72) with T >= 1", poses.shape)
    if betas.shape != (10,):
        raise _fail_shape(fname, "betas", "(10,)", betas.shape)
    if trans.shape != (T, 3):
        raise _fail_shape(fname, "trans", f"(T={T}, 3)", trans.shape)
    for k, a in arrs.items():
        if not np.isfinite(a).all():
            raise InputError(f"{fname}: key {k!r}: contains NaN or Inf values")
    fps = 30.0
    for k in _FPS_KEYS:
        if k in raw:
            try:
                fps = float(np.asarray(raw[k]).reshape(()))
            except (TypeError, ValueError):
                raise _fail_shape(fname, k, "a scalar", np.shape(raw[k])) from None
            break
    if not np.isfinite(fps) or fps <= 0:
        raise InputError(f"{fname}: key 'fps': expected a positive number, got {fps}")
    camera = raw.get("camera")
    if camera is None:
        camera = {k[len("camera_"):]: raw[k] for k in raw if isinstance(k, str) and k.startswith("camera_")} or None
    elif not isinstance(camera, dict):
        raise InputError(f"{fname}: key 'camera': expected a dict of arrays, got {type(camera).__name__}")
    if camera is not None:
        camera = {str(k): _camera_tensor(v, fname, k) for k, v in camera.items()}
    f32 = torch.float32
    return Motion(torch.as_tensor(poses, dtype=f32), torch.as_tensor(betas, dtype=f32),
                  torch.as_tensor(trans, dtype=f32), fps, camera)


def load_motion(path: str | Path) -> Motion:
    """Read an SMPL-style motion file (``.npz`` or ``.pkl``).

    Raises:
        InputError: missing file or key, unreadable content, NaN, bad fps.
        ShapeError: ``"motion.npz: key 'poses': expected (T, 72), got (10, 69)"``.
    """
    path = Path(path)
    fname = path.name
    if not path.is_file():
        raise InputError(f"{path}: no such motion file")
    if path.suffix == ".npz":
        raw = read_npz(path, "motion file")
    elif path.suffix == ".pkl":
        raw = load_pickle(path, "motion file")  # arrays and containers only: nothing in it runs
        if not isinstance(raw, dict):
            raise InputError(f"{fname}: expected a dict of arrays, got {type(raw).__name__}")
    else:
        raise InputError(f"{fname}: expected a .npz or .pkl motion file")
    return _validated(raw, fname)


def save_motion(path: str | Path, motion: Motion) -> Path:
    """Write ``motion`` as ``.npz`` (camera as ``camera_<name>`` keys) or ``.pkl`` (a dict)."""
    path = Path(path)
    _validated({"poses": motion.poses, "betas": motion.betas, "trans": motion.trans, "fps": motion.fps},
               path.name)
    arrays = {
        "poses": motion.poses.detach().cpu().numpy().astype(np.float32),
        "betas": motion.betas.detach().cpu().numpy().astype(np.float32),
        "trans": motion.trans.detach().cpu().numpy().astype(np.float32),
        "fps": np.float32(motion.fps),
    }
    cam = {k: v.detach().cpu().numpy() for k, v in (motion.camera or {}).items()}
    if path.suffix == ".npz":
        with atomic_write(path) as f:
            np.savez(f, **arrays, **{f"camera_{k}": v for k, v in cam.items()})
    elif path.suffix == ".pkl":
        if cam:
            arrays["camera"] = cam
        with atomic_write(path) as f:
            pickle.dump(arrays, f)
    else:
        raise InputError(f"{path.name}: expected a .npz or .pkl motion file")
    return path


def reorient_motion(motion: Motion, R: torch.Tensor, root: torch.Tensor) -> Motion:
    """Rotate a whole motion about the world origin by ``R``.

    SMPL rotates the global orientation about the root joint ``r`` and then adds ``trans``,
    so a posed point is ``G (x − r) + r + t``; applying R gives orientation ``R G`` and
    translation ``R (r + t) − r``.

    Args:
        motion: the clip.
        R: (3, 3) rotation, e.g. :data:`Z_UP_TO_Y_UP`.
        root: (3,) the root joint of the rest body for ``motion.betas`` (e.g.
            ``SMPLBody(..., ground="none")(betas=...).joints[0, 0]`` at zero pose).

    Returns:
        The rotated :class:`Motion`.
    """
    check_shape(R, [3, 3], name="R")
    check_shape(root, [3], name="root")
    R = R.to(torch.float64)
    r = root.to(torch.float64)
    poses = motion.poses.to(torch.float64).clone()
    poses[:, :3] = matrix_to_rotvec(R @ rotvec_to_matrix(poses[:, :3]))
    trans = (r + motion.trans.to(torch.float64)) @ R.T - r
    return replace(motion, poses=poses.to(motion.poses.dtype), trans=trans.to(motion.trans.dtype))
