"""The one body-model interface: parameters in, a posed triangle mesh out.

Every body model (Anny, SMPL-family files) returns a :class:`BodyOutput` in
relightnet's world frame: right-handed, +y up, the person faces +z (toward the
default camera, which sits on +z and looks along −z), metres. By default the
feet of the *rest* pose touch the y = 0 plane (``ground="rest"``); the pose and
translation then move the body from there.

Pose parameters are axis-angle rotation vectors whose axes are the *world*
axes of the rest pose (the SMPL convention): a bone's rotation is applied about
its joint, in its parent's posed frame, which coincides with the world frame
while the parent chain is at rest. Index 0 is the root (global orientation,
about the root joint); ``trans`` (B, 3) is added last, in world coordinates.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import torch
from torch import nn

from ..checks import InputError, check_finite, check_shape

__all__ = [
    "BodyOutput",
    "BodyModel",
    "vertex_normals",
    "rotvec_to_matrix",
    "matrix_to_rotvec",
    "compose_rotvecs",
    "GROUND_MODES",
]

#: ``ground`` options of every body model: ``"rest"`` shifts each body along y so that its
#: rest-pose mesh (zero pose, zero translation) has min y = 0; ``"frame"`` does it per output
#: mesh (the lowest vertex of every posed frame on y = 0, ``trans[:, 1]`` ignored);
#: ``"none"`` keeps the model's native origin (Anny: root joint at 0; SMPL: file's origin).
GROUND_MODES = ("rest", "frame", "none")


@dataclass(frozen=True)
class BodyOutput:
    """A batch of posed meshes sharing one topology.

    Attributes:
        verts: (B, V, 3) world-frame vertex positions (metres).
        faces: (F, 3) int64 triangles, counter-clockwise seen from outside.
        uv: (Vt, 2) texture coordinates in [0, 1], v up (OpenGL / OBJ convention).
        uv_faces: (F, 3) int64 indices into ``uv``, triangle by triangle like ``faces``.
        normals: (B, V, 3) unit, area-weighted vertex normals, pointing outward.
        joints: (B, J, 3) world-frame joint (bone head) positions.
        joint_names: the J joint names, in order.
    """

    verts: torch.Tensor
    faces: torch.Tensor
    uv: torch.Tensor
    uv_faces: torch.Tensor
    normals: torch.Tensor
    joints: torch.Tensor
    joint_names: tuple[str, ...] = field(default=())

    @property
    def batch_size(self) -> int:
        return self.verts.shape[0]

    def __getitem__(self, i: int | slice) -> BodyOutput:
        """Select batch elements (topology is shared)."""
        if isinstance(i, int):
            i = slice(i, i + 1 if i != -1 else None)
        return BodyOutput(
            self.verts[i], self.faces, self.uv, self.uv_faces, self.normals[i], self.joints[i], self.joint_names
        )


def vertex_normals(verts: torch.Tensor, faces: torch.Tensor, eps: float = 1e-12) -> torch.Tensor:
    """Unit area-weighted vertex normals.

    Each face adds its (unnormalised) cross product, whose length is twice its area,
    to its three vertices; the sums are normalised.

    Args:
        verts: (B, V, 3) or (V, 3) positions.
        faces: (F, 3) int64 counter-clockwise triangles.

    Returns:
        Normals of the shape of ``verts``, unit length (a vertex touching no face gets 0).
    """
    check_shape(faces, ["F", 3], name="faces")
    squeeze = verts.dim() == 2
    if squeeze:
        verts = verts[None]
    check_shape(verts, ["B", "V", 3], name="verts")
    f = faces.to(device=verts.device, dtype=torch.long)
    v0, v1, v2 = verts[:, f[:, 0]], verts[:, f[:, 1]], verts[:, f[:, 2]]
    fn = torch.linalg.cross(v1 - v0, v2 - v0, dim=-1)  # (B, F, 3)
    corners = f.T.reshape(1, -1, 1).expand(verts.shape[0], -1, 3)  # (B, 3F, 3): corner k of every face
    n = torch.zeros_like(verts).scatter_add_(1, corners, fn.repeat(1, 3, 1))
    n = n / n.norm(dim=-1, keepdim=True).clamp_min(eps)
    return n[0] if squeeze else n


def rotvec_to_matrix(rotvec: torch.Tensor) -> torch.Tensor:
    """Rodrigues: (..., 3) axis-angle vectors (radians) → (..., 3, 3) rotation matrices."""
    import roma  # imported on use: it loads torch._dynamo (about 2 s)

    check_shape(rotvec, ["...", 3], name="rotvec")
    return roma.rotvec_to_rotmat(rotvec)


def matrix_to_rotvec(R: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) rotation matrices → (..., 3) axis-angle vectors, angle in [0, π]."""
    import roma

    check_shape(R, ["...", 3, 3], name="R")
    return roma.rotmat_to_rotvec(R)


def compose_rotvecs(first: torch.Tensor, then: torch.Tensor) -> torch.Tensor:
    """Rotation vector of ``then ∘ first`` (apply ``first``, then ``then``), shapes (..., 3)."""
    return matrix_to_rotvec(rotvec_to_matrix(then) @ rotvec_to_matrix(first))


class BodyModel(nn.Module):
    """Base class of the body models: ``model(params) -> BodyOutput``.

    Subclasses set ``faces`` (F, 3), ``uv`` (Vt, 2), ``uv_faces`` (F, 3) buffers and
    ``joint_names``, and implement :meth:`_forward`. ``params`` is a mapping (or keyword
    arguments) with the keys listed in ``param_names``; missing keys take their defaults
    (rest pose, no translation, default shape), unknown keys raise :class:`InputError`.
    """

    faces: torch.Tensor
    uv: torch.Tensor
    uv_faces: torch.Tensor
    joint_names: tuple[str, ...]
    param_names: tuple[str, ...] = ("pose", "trans")

    def __init__(self, ground: str = "rest") -> None:
        super().__init__()
        if ground not in GROUND_MODES:
            raise InputError(f"ground: expected one of {GROUND_MODES}, got {ground!r}")
        self.ground = ground

    @property
    def num_verts(self) -> int:
        raise NotImplementedError

    @property
    def num_joints(self) -> int:
        return len(self.joint_names)

    def forward(self, params: Mapping | None = None, **kwargs) -> BodyOutput:
        """Pose the body.

        Args:
            params: mapping of parameter name → value (see the subclass), merged with ``kwargs``.

        Returns:
            A :class:`BodyOutput` of batch size B (the largest batch among the inputs;
            inputs of batch 1 broadcast).
        """
        merged = dict(params or {})
        merged.update(kwargs)
        unknown = sorted(set(merged) - set(self.param_names))
        if unknown:
            raise InputError(
                f"{type(self).__name__}: unknown parameter(s) {unknown}; expected some of {list(self.param_names)}"
            )
        return self._forward(merged)

    def _forward(self, params: dict) -> BodyOutput:
        raise NotImplementedError

    # Helpers shared by the subclasses -------------------------------------------------------

    def _finish(self, verts: torch.Tensor, joints: torch.Tensor, rest_min_y: torch.Tensor,
                trans: torch.Tensor) -> BodyOutput:
        """Ground, translate, and wrap world-frame verts (B, V, 3) / joints (B, J, 3).

        ``rest_min_y`` is (B,) the lowest y of the rest mesh in the same frame as ``verts``.
        """
        if self.ground == "rest":
            offset = torch.zeros_like(trans)
            offset[:, 1] = -rest_min_y
            shift = trans + offset
        elif self.ground == "frame":
            shift = trans.clone()
            shift[:, 1] = -verts[..., 1].amin(dim=1)
        else:
            shift = trans
        verts = verts + shift[:, None, :]
        joints = joints + shift[:, None, :]
        return BodyOutput(
            verts=verts,
            faces=self.faces,
            uv=self.uv,
            uv_faces=self.uv_faces,
            normals=vertex_normals(verts, self.faces),
            joints=joints,
            joint_names=tuple(self.joint_names),
        )

    def _batched(self, x, name: str, tail: list) -> torch.Tensor | None:
        """``x`` (or None) as a finite (B, *tail) tensor in the model's dtype and device."""
        if x is None:
            return None
        x = torch.as_tensor(x, dtype=self.dtype, device=self.faces.device)
        if x.dim() == len(tail):
            x = x[None]
        check_shape(x, ["B", *tail], name=name)
        check_finite(x, name)
        return x

    @property
    def dtype(self) -> torch.dtype:
        raise NotImplementedError


def broadcast_batch(tensors: dict[str, torch.Tensor], model_name: str) -> int:
    """The common batch size of (B_i, ...) tensors: equal sizes or 1; raise :class:`InputError` otherwise."""
    sizes = {k: v.shape[0] for k, v in tensors.items() if v is not None}
    big = {s for s in sizes.values() if s != 1}
    if len(big) > 1:
        raise InputError(f"{model_name}: inconsistent batch sizes {sizes}")
    return big.pop() if big else 1
