"""The one correspondence between the 33 BlazePose landmarks and points of the Anny body.

:data:`LANDMARK_SOURCES` says, for each of the 33 landmarks of
:data:`relightnet.segment.LANDMARK_NAMES`, which Anny point stands for it:

- ``("coco", label)``: a point of Anny's own COCO keypoint regressor
  (``anny.KeypointsRegressor.coco``: a fixed blend of mesh vertices; it has nose, eyes, ears,
  shoulders, elbows, wrists, hips, knees, ankles, big and small toes and heels);
- ``("joint", bone)``: the head of an Anny bone (hands: MediaPipe's pinky and index points
  are the knuckles, its thumb point the thumb's last joint);
- ``None``: no Anny point (inner/outer eye corners and mouth corners are too close to
  others to help a body fit); these landmarks get weight 0.

:class:`AnnyLandmarks` turns a posed body (vertices and joints) into (B, 33, 3) points in
the same order, with :attr:`AnnyLandmarks.mapped` (33,) saying which are defined.
"""

from __future__ import annotations

import torch
from torch import nn

from ..checks import InputError, check_shape
from ..segment.models import LANDMARK_NAMES

__all__ = ["LANDMARK_SOURCES", "AnnyLandmarks", "landmark_weights"]

_COCO_SAME = ("nose", "left_eye", "right_eye", "left_ear", "right_ear", "left_shoulder", "right_shoulder",
              "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hip", "right_hip", "left_knee",
              "right_knee", "left_ankle", "right_ankle", "left_heel", "right_heel")

#: BlazePose landmark name → Anny point: ("coco", regressor label), ("joint", bone name) or None.
LANDMARK_SOURCES: dict[str, tuple[str, str] | None] = {
    **{n: None for n in LANDMARK_NAMES},
    **{n: ("coco", n) for n in _COCO_SAME},
    "left_foot_index": ("coco", "left_big_toe"),
    "right_foot_index": ("coco", "right_big_toe"),
    "left_pinky": ("joint", "finger5-1.L"),
    "right_pinky": ("joint", "finger5-1.R"),
    "left_index": ("joint", "finger2-1.L"),
    "right_index": ("joint", "finger2-1.R"),
    "left_thumb": ("joint", "finger1-3.L"),
    "right_thumb": ("joint", "finger1-3.R"),
}


def landmark_weights(visibility: torch.Tensor, mapped: torch.Tensor, floor: float = 0.05) -> torch.Tensor:
    """Per-landmark weights from BlazePose's visibility: (..., 33) in [0, 1], 0 where unmapped.

    Args:
        visibility: (..., 33) visibility probabilities.
        mapped: (33,) bool, :attr:`AnnyLandmarks.mapped`.
        floor: weights below this are set to 0 (the model guesses those points).
    """
    check_shape(visibility, ["...", len(LANDMARK_NAMES)], name="visibility")
    w = visibility.clamp(0, 1) * mapped.to(visibility)
    return torch.where(w < floor, torch.zeros_like(w), w)


class AnnyLandmarks(nn.Module):
    """Anny's points for the 33 BlazePose landmarks (:data:`LANDMARK_SOURCES`).

    Args:
        body: an :class:`relightnet.body.AnnyBody` (its ``anny`` model and ``joint_names``).

    Calling it on ``(verts (B, V, 3), joints (B, J, 3))`` returns (B, 33, 3) points; rows of
    unmapped landmarks are zero. ``mapped`` (33,) bool says which rows are defined.
    """

    def __init__(self, body) -> None:
        super().__init__()
        import anny

        reg = anny.KeypointsRegressor.coco(body.anny)
        labels = list(reg.labels)
        weights = reg.regression_weights.detach().to(torch.float32)
        names = list(body.joint_names)
        rows, coco_slot, joint_slot, joint_idx = [], [], [], []
        for i, name in enumerate(LANDMARK_NAMES):
            src = LANDMARK_SOURCES[name]
            if src is None:
                continue
            kind, label = src
            if kind == "coco":
                if label not in labels:
                    raise InputError(f"anny COCO regressor has no {label!r} (labels: {labels})")
                coco_slot.append(i)
                rows.append(weights[labels.index(label)])
            else:
                if label not in names:
                    raise InputError(f"Anny has no bone {label!r}")
                joint_slot.append(i)
                joint_idx.append(names.index(label))
        # Sparse: only the vertices some landmark uses (a gather, then a small matmul).
        W = torch.stack(rows)
        used = torch.nonzero(W.abs().sum(0) > 0).flatten()
        self.register_buffer("coco_weights", W[:, used].to(body.dtype), persistent=False)
        self.register_buffer("coco_vertices", used, persistent=False)
        self.register_buffer("coco_slot", torch.tensor(coco_slot, dtype=torch.long), persistent=False)
        self.register_buffer("joint_slot", torch.tensor(joint_slot, dtype=torch.long), persistent=False)
        self.register_buffer("joint_index", torch.tensor(joint_idx, dtype=torch.long), persistent=False)
        mapped = torch.zeros(len(LANDMARK_NAMES), dtype=torch.bool)
        mapped[self.coco_slot] = True
        mapped[self.joint_slot] = True
        self.register_buffer("mapped", mapped, persistent=False)

    def forward(self, verts: torch.Tensor, joints: torch.Tensor) -> torch.Tensor:
        check_shape(verts, ["B", "V", 3], name="verts")
        return self.from_subset(verts[:, self.coco_vertices], joints)

    def from_subset(self, coco_verts: torch.Tensor, joints: torch.Tensor) -> torch.Tensor:
        """Like calling the module, from (B, U, 3) positions of the vertices ``coco_vertices`` only."""
        check_shape(coco_verts, ["B", len(self.coco_vertices), 3], name="coco_verts")
        coco = torch.einsum("ks,bsd->bkd", self.coco_weights.to(coco_verts), coco_verts)
        return self.from_regressed(coco, joints)

    def from_regressed(self, coco: torch.Tensor, joints: torch.Tensor) -> torch.Tensor:
        """(B, 33, 3) from the regressed points (B, Kc, 3) (rows ``coco_slot``) and joints (B, J, 3)."""
        check_shape(joints, ["B", "J", 3], name="joints")
        return self.assemble(coco, joints[:, self.joint_index])

    def assemble(self, coco: torch.Tensor, hands: torch.Tensor) -> torch.Tensor:
        """(B, 33, 3) from the regressed points (B, Kc, 3) and the hand joints (B, Kh, 3) (rows ``joint_slot``)."""
        d = check_shape(coco, ["B", len(self.coco_slot), 3], name="coco")
        check_shape(hands, [d["B"], len(self.joint_slot), 3], name="hands")
        out = coco.new_zeros(d["B"], len(LANDMARK_NAMES), 3)
        out = out.index_copy(1, self.coco_slot, coco)
        return out.index_copy(1, self.joint_slot, hands)
