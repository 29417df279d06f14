"""The fit's view of Anny: the fitted bones' rotations → landmark points and silhouette vertices.

:class:`FitBody` wraps an :class:`relightnet.body.AnnyBody` (``ground="rest"``, the one
every command renders with) with the landmark correspondence (:class:`AnnyLandmarks`), the
bone indices of :data:`FIT_BONES` and a fixed subset of vertices for the silhouette term.
Bodies are posed in the camera's view space: the root rotation is the orientation relative
to the camera and ``trans`` the translation (the person faces +z, toward the camera, at zero).
"""

from __future__ import annotations

import torch
from torch import nn

from ..body.anny_model import ANNY_TO_WORLD, PHENOTYPES, anny_to_world
from ..body.base import rotvec_to_matrix
from ..checks import check_shape
from .landmarks import AnnyLandmarks
from .prior import FIT_BONES

__all__ = ["FitBody", "SHAPE_NAMES", "phenotype_from_free"]

#: The phenotype values a shape fit frees (the others keep :data:`relightnet.body.PHENOTYPES` defaults).
SHAPE_NAMES = ("height", "weight", "proportions")
_SILHOUETTE_STRIDE = 24


def phenotype_from_free(free: torch.Tensor, base: torch.Tensor) -> torch.Tensor:
    """(1, 6) phenotype: ``base`` (6,) with the :data:`SHAPE_NAMES` entries from unconstrained ``free`` (3,).

    A sigmoid keeps each value inside its :data:`PHENOTYPES` range.
    """
    check_shape(free, [len(SHAPE_NAMES)], name="free")
    names = list(PHENOTYPES)
    out = base.clone().to(free)
    for j, n in enumerate(SHAPE_NAMES):
        lo, hi, _ = PHENOTYPES[n]
        out = out.index_put((torch.tensor([names.index(n)]),), (lo + (hi - lo) * torch.sigmoid(free[j]))[None])
    return out[None]


class FitBody(nn.Module):
    """Anny posed by the fitted bones.

    Args:
        body: an :class:`relightnet.body.AnnyBody` (made here when None; ``ground`` must be ``"rest"``).

    ``forward(sub (B, N, 3), trans (B, 3), phenotype (1, 6))`` returns ``(points (B, 33, 3),
    silhouette vertices (B, S, 3), BodyOutput)``; N = len(FIT_BONES).
    """

    def __init__(self, body=None) -> None:
        super().__init__()
        if body is None:
            from ..body import AnnyBody

            body = AnnyBody()
        self.body = body
        self.landmarks = AnnyLandmarks(body)
        idx = [body.joint_index(b) for b in FIT_BONES]
        self.register_buffer("bone_index", torch.tensor(idx, dtype=torch.long), persistent=False)
        self.register_buffer("silhouette_vertices", torch.arange(0, body.num_verts, _SILHOUETTE_STRIDE),
                             persistent=False)
        # What :meth:`points` needs: the regressor vertices' dense bone weights, the silhouette
        # vertices' sparse ones.
        dense = body.anny.dense_vertex_bone_weights
        self.register_buffer("coco_bone_weights", dense[self.landmarks.coco_vertices].to(body.dtype),
                             persistent=False)
        sil = self.silhouette_vertices
        self.register_buffer("sil_bones", body.anny.vertex_bone_indices[sil].long(), persistent=False)
        self.register_buffer("sil_weights", body.anny.vertex_bone_weights[sil].to(body.dtype), persistent=False)

    @property
    def num_joints(self) -> int:
        return self.body.num_joints

    def full_pose(self, sub: torch.Tensor) -> torch.Tensor:
        """(B, N, 3) fitted-bone rotations → (B, J, 3) all bones (others zero)."""
        d = check_shape(sub, ["B", len(FIT_BONES), 3], name="sub")
        full = sub.new_zeros(d["B"], self.num_joints, 3)
        return full.index_copy(1, self.bone_index, sub)

    def forward(self, sub: torch.Tensor, trans: torch.Tensor, phenotype: torch.Tensor):
        out = self.body(pose=self.full_pose(sub), trans=trans, phenotype=phenotype)
        pts = self.landmarks(out.verts, out.joints)
        return pts, out.verts[:, self.silhouette_vertices], out

    def rest(self, phenotype: torch.Tensor) -> dict:
        """The rest body of a (1, 6) phenotype, for :meth:`points` (differentiable in ``phenotype``).

        Skinning is linear, so each regressed landmark is Σ_bones T_b a_b with a_b = Σ_v w_v W_vb (v, 1),
        and each silhouette vertex Σ_b T_b W_vb (v, 1): ``blend`` (J·4, K + S) holds those a, once
        per shape. Also the rest bone poses and the ground offset (world frame, ``ground="rest"``).
        """
        anny = self.body.anny
        J = self.num_joints
        eye = torch.eye(4, dtype=self.body.dtype).expand(1, J, 4, 4)
        raw = anny(pose_parameters=eye, phenotype_kwargs=phenotype)
        zero = self.body(pose=torch.zeros(1, J, 3, dtype=self.body.dtype), phenotype=phenotype)
        offset = (zero.joints[0] - anny_to_world(raw["bone_poses"][0, :, :3, 3])).mean(0)
        rv = raw["rest_vertices"][0]
        cv = rv[self.landmarks.coco_vertices]
        vh = torch.cat([cv, torch.ones_like(cv[:, :1])], 1)
        wv = (self.landmarks.coco_weights.to(rv)[:, :, None] * vh[None]).transpose(1, 2)  # (K, 4, U)
        coco = (wv @ self.coco_bone_weights.to(rv)).transpose(1, 2)  # (K, J, 4)
        sv = rv[self.silhouette_vertices]
        svh = torch.cat([sv, torch.ones_like(sv[:, :1])], 1)  # (S, 4)
        sil = sv.new_zeros(len(sv), self.num_joints, 4)
        sil = sil.index_put((torch.arange(len(sv))[:, None].expand_as(self.sil_bones), self.sil_bones),
                            self.sil_weights.to(sv)[..., None] * svh[:, None], accumulate=True)
        # (J·4, K + S): one matmul with the bone transforms gives every landmark and silhouette point
        blend = torch.cat([coco, sil]).reshape(-1, self.num_joints * 4).T
        return {"blend": blend, "bone_poses": raw["rest_bone_poses"], "offset": offset}

    def points(self, sub: torch.Tensor, trans: torch.Tensor, rest: dict) -> tuple[torch.Tensor, torch.Tensor]:
        """Landmark points (B, 33, 3) and silhouette vertices (B, S, 3) without skinning the whole mesh.

        The same body as :meth:`forward`, for the shape of ``rest`` (:meth:`rest`).
        """
        d = check_shape(sub, ["B", len(FIT_BONES), 3], name="sub")
        C = ANNY_TO_WORLD.to(sub)
        R = C.T @ rotvec_to_matrix(self.full_pose(sub)) @ C
        delta = torch.zeros(d["B"], self.num_joints, 4, 4, dtype=sub.dtype)
        delta[..., :3, :3] = R
        delta[..., 3, 3] = 1.0
        T, poses = self.body.anny.get_bone_transforms(delta, rest["bone_poses"])
        M = T[..., :3, :].transpose(1, 2).reshape(d["B"], 3, self.num_joints * 4)  # (B, 3, J·4)
        p = anny_to_world((M @ rest["blend"]).transpose(1, 2))  # (B, K + S, 3)
        shift = (rest["offset"] + trans)[:, None]
        joints = anny_to_world(poses[..., :3, 3]) + shift
        k = len(self.landmarks.coco_slot)
        return self.landmarks.from_regressed(p[:, :k] + shift, joints), p[:, k:] + shift
