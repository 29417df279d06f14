"""Geometry beyond the body: per-vertex offsets along the normal (the SMPL+D idea).

An offset d_v moves vertex v along its posed normal: ``v' = v + d_v n_v``. Applied after
skinning, it poses with the body in every frame (the normal turns with the skinned surface).
"""

from __future__ import annotations

import torch

from ..checks import check_shape

__all__ = ["apply_offsets"]


def apply_offsets(verts: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    """Move every vertex along its normal by its offset.

    Args:
        verts: (B, V, 3) posed positions. normals: (B, V, 3) unit posed normals.
        offsets: (V,) metres along the normal (positive: outward).

    Returns:
        (B, V, 3) displaced positions (differentiable in all three).
    """
    d = check_shape(verts, ["B", "V", 3], name="verts")
    check_shape(normals, [d["B"], d["V"], 3], name="normals")
    check_shape(offsets, [d["V"]], name="offsets")
    return verts + offsets.to(verts)[None, :, None] * normals
