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

__all__ = ["FitBody", "SHAPE_NAMES", "phenotype_from_free", "rest_near"]

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


def rest_near(rest: dict, jacobian: dict, delta: torch.Tensor) -> dict:
    """The rest body (:meth:`FitBody.rest`) at free shape values ``free₀ + delta``, to first order.

    Args:
        rest: :meth:`FitBody.rest` at free₀; jacobian: its derivatives (:meth:`FitBody.rest_linearised`),
            each entry (F, ...) for the F = len(SHAPE_NAMES) free values; delta: (F,).
    """
    check_shape(delta, [len(SHAPE_NAMES)], name="delta")
    return {k: rest[k] + torch.tensordot(delta.to(rest[k]), jacobian[k], 1) for k in rest}


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
        self._tree(body)

    def _tree(self, body) -> None:
        """Each bone's nearest fitted ancestor (or itself), each fitted bone's fitted parent."""
        parents = list(body.anny.bone_parents)
        slot = {int(b): i for i, b in enumerate(self.bone_index)}

        def fitted(j: int) -> int:
            while j not in slot:
                j = int(parents[j])
            return j

        group = [fitted(j) for j in range(self.num_joints)]
        parent = [group[0]] + [fitted(int(parents[int(b)])) for b in self.bone_index[1:]]
        self.register_buffer("group", torch.tensor(group), persistent=False)
        self.register_buffer("group_slot", torch.tensor([slot[g] for g in group]), persistent=False)
        self.register_buffer("parent_index", torch.tensor(parent), persistent=False)
        self.parent_slot = [slot[p] for p in parent]
        depth = [0] * len(parent)
        for i in range(1, len(parent)):  # FIT_BONES lists parents before children
            depth[i] = depth[self.parent_slot[i]] + 1
        #: The fitted bones by depth in the tree (each level's frames are one batched product).
        self.levels = [[i for i in range(len(parent)) if depth[i] == lv] for lv in range(max(depth) + 1)]
        self.register_buffer("reference_axes", body.anny.reference_bone_orientations[self.bone_index].to(body.dtype),
                             persistent=False)

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

        Only the fitted bones move, so every other bone's posed frame is its nearest fitted
        ancestor's times a constant: W_j = W_f (W⁰_f)⁻¹ W⁰_j (W⁰: the posed frames at zero
        rotations). Skinning is linear, so each landmark, hand joint and silhouette vertex is
        Σ_f W_f b_f with constant 4-vectors b: ``blend`` (N·4, P) holds them, once per shape.
        A fitted bone's frame is W_f = W_a M_f D_f (a: its fitted parent, M_f = (W⁰_a)⁻¹ W⁰_f,
        D_f its rotation in the bone's reference axes: Anny's ``local-ref`` convention).
        """
        anny = self.body.anny
        J = self.num_joints
        eye = torch.eye(4, dtype=self.body.dtype).expand(1, J, 4, 4)
        raw = anny(pose_parameters=eye, phenotype_kwargs=phenotype)
        # The body's ``ground="rest"`` shift, from this same zero-pose pass (no second forward).
        min_y = self.body._zero_pose_min_y(raw)[0]
        offset = torch.stack([torch.zeros_like(min_y), -min_y, torch.zeros_like(min_y)])
        W0, P = raw["bone_poses"][0], raw["rest_bone_poses"][0]
        W0f_inv = torch.linalg.inv(W0[self.bone_index])  # (N, 4, 4)
        C = W0f_inv[self.group_slot] @ W0 @ torch.linalg.inv(P)  # (J, 4, 4): T_j = W_f(j) C_j
        rv = raw["rest_vertices"][0]
        cv = rv[self.landmarks.coco_vertices]
        vh = torch.cat([cv, torch.ones_like(cv[:, :1])], 1)
        wv = (self.landmarks.coco_weights.to(rv)[:, :, None] * vh[None]).transpose(1, 2)  # (K, 4, U)
        coco = (wv @ self.coco_bone_weights.to(rv)).transpose(1, 2)  # (K, J, 4): Σ_v w W_vj (v, 1)
        sv = rv[self.silhouette_vertices]
        svh = torch.cat([sv, torch.ones_like(sv[:, :1])], 1)  # (S, 4)
        sil = sv.new_zeros(len(sv), J, 4)
        sil = sil.index_put((torch.arange(len(sv))[:, None].expand_as(self.sil_bones), self.sil_bones),
                            self.sil_weights.to(sv)[..., None] * svh[:, None], accumulate=True)
        per_bone = torch.einsum("jab,pjb->pja", C, torch.cat([coco, sil]))  # (K + S, J, 4) in W_f(j) terms
        pts = per_bone.new_zeros(per_bone.shape[0], len(FIT_BONES), 4).index_add(1, self.group_slot, per_bone)
        hj = self.landmarks.joint_index
        heads = (W0f_inv[self.group_slot[hj]] @ W0[hj][..., 3:])[..., 0]  # (H, 4): bone heads
        hands = heads.new_zeros(len(hj), len(FIT_BONES), 4).index_put(
            (torch.arange(len(hj)), self.group_slot[hj]), heads)
        blend = torch.cat([pts, hands]).reshape(-1, len(FIT_BONES) * 4).T  # (N·4, K + S + H)
        M = torch.linalg.inv(W0[self.parent_index]) @ W0[self.bone_index]
        M[0] = W0[self.bone_index[0]]  # the root: W_root = W⁰_root D_root
        return {"blend": blend, "M": M, "offset": offset}

    @torch.no_grad()
    def rest_linearised(self, free: torch.Tensor, base: torch.Tensor, step: float = 1e-2) -> tuple[dict, dict]:
        """The rest body at free shape values ``free`` (F,) and its derivatives in each (forward
        differences of ``step``; the sigmoid's slope is at most 1/4, so the phenotype moves at most
        ``step``/4 of its range): what :func:`rest_near` needs. ``base``: (6,) the other phenotype values.
        """
        check_shape(free, [len(SHAPE_NAMES)], name="free")
        rest = self.rest(phenotype_from_free(free, base))
        jac = {k: [] for k in rest}
        for j in range(len(SHAPE_NAMES)):
            moved = self.rest(phenotype_from_free(free + step * torch.eye(len(SHAPE_NAMES), dtype=free.dtype)[j], base))
            for k in rest:
                jac[k].append((moved[k] - rest[k]) / step)
        return rest, {k: torch.stack(v) for k, v in jac.items()}

    def points(self, sub: torch.Tensor, trans: torch.Tensor, rest: dict) -> tuple[torch.Tensor, torch.Tensor]:
        """Landmark points (B, 33, 3) and silhouette vertices (B, S, 3) without skinning the whole mesh.

        The same body as :meth:`forward`, for the shape of ``rest`` (:meth:`rest`).
        """
        d = check_shape(sub, ["B", len(FIT_BONES), 3], name="sub")
        CU = ANNY_TO_WORLD.to(sub) @ self.reference_axes.to(sub)  # (N, 3, 3)
        D = CU.transpose(1, 2) @ rotvec_to_matrix(sub) @ CU  # (B, N, 3, 3): rotations in reference axes
        M = rest["M"].to(sub)
        done, row = None, {}  # the frames so far (B, n, 4, 4), and each bone's row in them
        for level in self.levels:
            if done is None:
                base = M[level].expand(d["B"], -1, 4, 4)
            else:
                base = done[:, [row[self.parent_slot[i]] for i in level]] @ M[level]
            f = torch.cat([base[..., :3] @ D[:, level], base[..., 3:]], -1)
            done = f if done is None else torch.cat([done, f], 1)
            row.update({i: len(row) + k for k, i in enumerate(level)})
        W = done[:, [row[i] for i in range(len(FIT_BONES))], :3, :]  # (B, N, 3, 4)
        p = anny_to_world((W.transpose(1, 2).reshape(d["B"], 3, -1) @ rest["blend"]).transpose(1, 2))
        p = p + (rest["offset"] + trans)[:, None]
        k, s = len(self.landmarks.coco_slot), len(self.silhouette_vertices)
        return self.landmarks.assemble(p[:, :k], p[:, k + s:]), p[:, k:k + s]
