"""SMPL-family model files supplied by the user, behind the :class:`BodyModel` interface.

relightnet never ships SMPL data (its licence forbids it); the user points
:class:`SMPLBody` at their own ``.npz`` or chumpy-free ``.pkl``. The arrays are read
here and handed to ``smplx.SMPL`` as its ``data_struct``, so the forward pass is
smplx's own linear blend skinning. Keys read (see :data:`SMPL_KEYS`):

- ``v_template`` (V, 3), ``f`` (F, 3) triangles, ``J_regressor`` (J, V) (dense or
  scipy-sparse), ``weights`` (V, J), ``posedirs`` (V, 3, 9(J−1)),
  ``shapedirs`` (V, 3, S), ``kintree_table`` (2, J) (row 0: parents);
- optional ``vt`` (Vt, 2) and ``ft`` (F, 3) UVs. Official SMPL files have none; the
  fallback is a spherical projection of the template about its centre
  (u = ½ + atan2(x, z)/2π, v = ½ + asin(ŷ)/π, ``uv_faces = faces``), which is
  continuous except across the seam behind the body (u wraps there) — fine for
  colour-by-region, not for painted textures.

Frame: SMPL files are y up, facing +z, metres, like relightnet's world, so the
conversion :func:`smpl_to_world` is the identity. Any joint count works (SMPL 24,
SMPL-H 52, ...), with pose ``(B, J, 3)`` axis-angle in SMPL's usual convention
(parent-relative rotations in the rest-pose world axes; index 0 = global orientation).
"""

from __future__ import annotations

import contextlib
import io
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import torch

from ..checks import InputError, ShapeError
from ..io.arrays import read_npz
from ..io.safe_pickle import load_pickle
from .base import BodyModel, BodyOutput, broadcast_batch

__all__ = ["SMPLBody", "SMPL_KEYS", "load_smpl_file", "smpl_to_world", "spherical_uv"]

#: Keys an SMPL model file must hold.
SMPL_KEYS = ("v_template", "f", "J_regressor", "weights", "posedirs", "shapedirs", "kintree_table")


def smpl_to_world(x: torch.Tensor) -> torch.Tensor:
    """SMPL's frame (y up, facing +z) is relightnet's world frame: returns ``x`` unchanged."""
    return x


def load_smpl_file(path: str | Path) -> dict[str, np.ndarray]:
    """Read the arrays of an SMPL-family ``.npz`` / ``.pkl`` and check their shapes.

    Returns:
        dict with the :data:`SMPL_KEYS` (dense float64 / int64 numpy arrays) and ``vt``/``ft``
        when present.

    Raises:
        InputError: unreadable file, missing key, chumpy pickle.
        ShapeError: ``"{file}: key 'weights': expected (V=6890, J=24), got (6890, 23)"``.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such SMPL model file")
    if path.suffix == ".npz":
        raw = read_npz(path, "SMPL model file", SMPL_KEYS + ("vt", "ft"))
    elif path.suffix == ".pkl":
        # Arrays, sparse matrices and chumpy arrays only (official SMPL files): nothing in it runs.
        raw = load_pickle(path, "SMPL model file")
        if not isinstance(raw, dict):
            raise InputError(f"{path.name}: expected a dict of arrays, got {type(raw).__name__}")
    else:
        raise InputError(f"{path.name}: expected an .npz or .pkl SMPL model file")
    return _checked_arrays(raw, path.name)


def _checked_arrays(raw: dict, name: str) -> dict[str, np.ndarray]:
    """The SMPL arrays of ``raw`` as float64 / int64, every shape, index and value checked."""
    missing = [k for k in SMPL_KEYS if k not in raw]
    if missing:
        raise InputError(f"{name}: missing key(s) {missing} (an SMPL file needs {list(SMPL_KEYS)})")
    out = {}
    for k in SMPL_KEYS + ("vt", "ft"):
        if k not in raw:
            continue
        a = raw[k]
        if not isinstance(a, np.ndarray) or a.dtype.kind not in "biuf":
            raise InputError(f"{name}: key {k!r}: expected a numeric array, got {type(a).__name__}"
                             f"{'' if not isinstance(a, np.ndarray) else ' of ' + str(a.dtype)}")
        if not np.isfinite(a).all():
            raise InputError(f"{name}: key {k!r}: contains NaN or Inf values")
        out[k] = a.astype(np.int64) if k in ("f", "ft", "kintree_table") else a.astype(np.float64)
    v, kt = out["v_template"], out["kintree_table"]
    V = v.shape[0] if v.ndim == 2 and v.shape[0] > 0 else None
    J = kt.shape[-1] if kt.ndim == 2 and kt.shape[-1] > 0 else None
    names = {"v_template": "(V, 3)", "f": "(F, 3)", "J_regressor": f"(J={J}, V={V})",
             "weights": f"(V={V}, J={J})", "posedirs": f"(V={V}, 3, {9 * (J or 1) - 9})",
             "shapedirs": f"(V={V}, 3, S)", "kintree_table": "(2, J)"}
    expect = {
        "v_template": (V, 3), "f": (None, 3), "J_regressor": (J, V), "weights": (V, J),
        "posedirs": (V, 3, 9 * (J or 1) - 9), "shapedirs": (V, 3, None), "kintree_table": (2, J),
    }
    for k, shape in expect.items():
        a = out[k]
        if V is None or J is None or a.ndim != len(shape) or 0 in a.shape[:1] or any(
                s is not None and s != n for s, n in zip(shape, a.shape, strict=True)):
            raise ShapeError(f"{name}: key {k!r}: expected {names[k]}, got {tuple(a.shape)}")
    if out["shapedirs"].shape[2] < 1:
        raise ShapeError(f"{name}: key 'shapedirs': expected at least one shape component, got 0")
    if out["f"].min() < 0 or out["f"].max() >= V:
        raise InputError(f"{name}: key 'f': indices outside [0, {V})")
    parents = kt[0, 1:]
    if (parents < 0).any() or (parents >= np.arange(1, J)).any():
        raise InputError(f"{name}: key 'kintree_table': each joint's parent must be an earlier joint")
    if ("vt" in out) != ("ft" in out):
        raise InputError(f"{name}: 'vt' and 'ft' come together (UVs), got only one")
    if "vt" in out:
        vt, ft = out["vt"], out["ft"]
        if vt.ndim != 2 or vt.shape[-1] != 2 or ft.shape != out["f"].shape:
            raise ShapeError(f"{name}: UVs: expected vt (Vt, 2), ft {out['f'].shape}, got {vt.shape}, {ft.shape}")
        if ft.min() < 0 or ft.max() >= len(vt):
            raise InputError(f"{name}: key 'ft': indices outside [0, {len(vt)})")
    return out


def spherical_uv(verts: torch.Tensor) -> torch.Tensor:
    """Fallback UVs: (V, 3) template → (V, 2) spherical projection about the bounding-box centre."""
    p = verts - (verts.amax(0) + verts.amin(0)) / 2
    p = p / p.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    u = 0.5 + torch.atan2(p[:, 0], p[:, 2]) / (2 * math.pi)
    v = 0.5 + torch.asin(p[:, 1].clamp(-1, 1)) / math.pi
    return torch.stack([u, v], dim=-1)


class SMPLBody(BodyModel):
    """An SMPL-family model file as a :class:`BodyModel`.

    Parameters (mapping or keyword arguments of ``forward``): ``pose`` (B, J, 3) / (J, 3) or
    (B, 3J) axis-angle, ``betas`` (B, S') / (S',) with S' ≤ ``num_betas`` (zero-padded),
    ``trans`` (B, 3) / (3,). Missing: zeros.

    Args:
        model_path: the user's ``.npz`` / ``.pkl`` (see :func:`load_smpl_file`).
        num_betas: shape components used (at most the file's S).
        dtype, device: of the buffers.
        ground: see :data:`relightnet.body.base.GROUND_MODES`.
    """

    param_names = ("pose", "trans", "betas")

    def __init__(self, model_path: str | Path, num_betas: int = 10, dtype: torch.dtype = torch.float32,
                 device: torch.device | str | None = None, ground: str = "rest") -> None:
        super().__init__(ground=ground)
        import smplx

        data = load_smpl_file(model_path)
        self.path = Path(model_path)
        n_joints = data["kintree_table"].shape[1]
        self.num_betas = min(int(num_betas), data["shapedirs"].shape[2])
        # smplx selects extra "joints" at fixed vertex ids (SMPL-H numbering); point them at vertex 0
        # and drop them: only the regressed joints are returned.
        vids = {k: 0 for k in ("nose", "reye", "leye", "rear", "lear")}
        struct = SimpleNamespace(**{k: data[k] for k in SMPL_KEYS})
        with contextlib.redirect_stdout(io.StringIO()):  # smplx prints a warning for < 300 betas
            self.smpl = smplx.SMPL(
                model_path=str(self.path), data_struct=struct, num_betas=self.num_betas,
                create_betas=False, create_global_orient=False, create_body_pose=False, create_transl=False,
                dtype=dtype, vertex_ids=vids, use_hands=False, use_feet_keypoints=False,
            ).to(device)
        self.num_betas = int(self.smpl.num_betas)  # smplx caps files with < 300 components at 10
        self._dtype = dtype
        dev = self.smpl.v_template.device
        self.register_buffer("faces", torch.as_tensor(data["f"], dtype=torch.int64, device=dev), persistent=False)
        if "vt" in data:
            uv = torch.as_tensor(data["vt"], dtype=dtype, device=dev)
            uv_faces = torch.as_tensor(data["ft"], dtype=torch.int64, device=dev)
        else:
            uv = spherical_uv(self.smpl.v_template.to(torch.float64)).to(dtype)
            uv_faces = self.faces.clone()
        self.register_buffer("uv", uv, persistent=False)
        self.register_buffer("uv_faces", uv_faces, persistent=False)
        self.joint_names = tuple(f"joint{i:02d}" for i in range(n_joints))
        if n_joints == 24:
            self.joint_names = SMPL_JOINT_NAMES

    @property
    def dtype(self) -> torch.dtype:
        return self._dtype

    @property
    def num_verts(self) -> int:
        return self.smpl.v_template.shape[0]

    def _forward(self, params: dict) -> BodyOutput:
        dev, dtype, J = self.faces.device, self.dtype, self.num_joints
        pose = params.get("pose")
        if pose is not None:
            pose = torch.as_tensor(pose, dtype=dtype, device=dev)
            if pose.dim() == 2 and pose.shape[-1] == 3 * J:
                pose = pose.reshape(-1, J, 3)
        pose = self._batched(pose, "pose", [J, 3])
        betas = self._batched(params.get("betas"), "betas", ["S"])
        trans = self._batched(params.get("trans"), "trans", [3])
        if betas is not None and betas.shape[1] > self.num_betas:
            raise ShapeError(f"betas: expected at most {self.num_betas} components, got {betas.shape[1]}")
        b = broadcast_batch({"pose": pose, "betas": betas, "trans": trans}, "SMPLBody")
        pose = torch.zeros(b, J, 3, dtype=dtype, device=dev) if pose is None else pose.expand(b, J, 3)
        full = torch.zeros(b, self.num_betas, dtype=dtype, device=dev)
        if betas is not None:
            full[:, : betas.shape[1]] = betas
        trans = torch.zeros(b, 3, dtype=dtype, device=dev) if trans is None else trans.expand(b, 3)
        out = self.smpl(betas=full, global_orient=pose[:, 0], body_pose=pose[:, 1:].reshape(b, -1))
        verts = smpl_to_world(out.vertices)
        joints = smpl_to_world(out.joints[:, :J])
        # Zero pose is the identity skinning: the rest mesh is v_template + shapedirs · betas.
        rest_y = self.smpl.v_template[:, 1] + full @ self.smpl.shapedirs[:, 1, :].T
        return self._finish(verts, joints, rest_y.amin(dim=1), trans)


#: The 24 SMPL joint names, in file order.
SMPL_JOINT_NAMES = (
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
    "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head",
    "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist",
    "left_hand", "right_hand",
)
