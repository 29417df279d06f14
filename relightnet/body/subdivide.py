"""One step of midpoint subdivision of some faces of a triangle mesh (no smoothing).

Every edge of a selected face gets one new vertex at its midpoint and the face becomes
four: ``(a, ab, ca)``, ``(ab, b, bc)``, ``(ca, bc, c)``, ``(ab, bc, ca)`` (the winding is
kept). The new vertices are numbered after the old ones, one per distinct edge, so that
the same topology can be applied to every frame of a clip (:func:`midpoint_values`).
A selected face that shares an edge with an unselected one would leave a T-junction
there; callers select whole connected pieces (a garment's outer side) to avoid that.

Shapes: V vertices, F faces, M new midpoint vertices.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from ..checks import InputError, check_shape

__all__ = ["SubdividedFaces", "subdivide_faces", "midpoint_values"]


@dataclass(frozen=True, eq=False)
class SubdividedFaces:
    """The topology of one midpoint-subdivision step (:func:`subdivide_faces`).

    Attributes:
        faces: (F − S + 4S, 3) int64: the unselected faces in their order, then each selected
            face replaced in place by its four children (so face i's children are consecutive).
        edges: (M, 2) int64 endpoints (a < b) of the edge whose midpoint is vertex ``n_verts + i``.
        n_verts: V, the vertex count before subdivision.
        parent: (F − S + 4S,) int64 the original face each new face comes from.
    """

    faces: torch.Tensor
    edges: torch.Tensor
    n_verts: int
    parent: torch.Tensor

    @property
    def midpoints(self) -> torch.Tensor:
        """(M, 3) int64 rows (midpoint vertex, endpoint a, endpoint b)."""
        m = torch.arange(self.edges.shape[0], dtype=torch.int64) + self.n_verts
        return torch.cat([m[:, None], self.edges], 1)


def subdivide_faces(faces: torch.Tensor, n_verts: int, select: torch.Tensor) -> SubdividedFaces:
    """Split the selected faces into four at their edges' midpoints.

    Args:
        faces: (F, 3) int64 triangles into V = ``n_verts`` vertices.
        n_verts: V. select: (F,) bool, the faces to split.

    Returns:
        :class:`SubdividedFaces`.
    """
    check_shape(faces, ["F", 3], name="faces")
    check_shape(select, [faces.shape[0]], name="select")
    faces = faces.long()
    if faces.numel() and (int(faces.min()) < 0 or int(faces.max()) >= n_verts):
        raise InputError(f"faces: expected indices in [0, {n_verts}), got [{int(faces.min())}, {int(faces.max())}]")
    sel = select.bool()
    f = faces[sel]
    e = torch.stack([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]], 1)  # (S, 3, 2): ab, bc, ca
    key = e.sort(dim=2).values.reshape(-1, 2)
    code, inv = torch.unique(key[:, 0] * n_verts + key[:, 1], return_inverse=True)  # 1-D: far faster than dim=0
    edges = torch.stack([code // n_verts, code % n_verts], 1)
    mid = (inv + n_verts).reshape(-1, 3)
    ab, bc, ca = mid[:, 0], mid[:, 1], mid[:, 2]
    a, b, c = f[:, 0], f[:, 1], f[:, 2]
    kids = torch.stack([torch.stack([a, ab, ca], 1), torch.stack([ab, b, bc], 1), torch.stack([ca, bc, c], 1),
                        torch.stack([ab, bc, ca], 1)], 1)  # (S, 4, 3)
    count = torch.where(sel, 4, 1)
    parent = torch.repeat_interleave(torch.arange(faces.shape[0]), count)
    out = faces[parent].clone()
    first = torch.cumsum(count, 0) - count  # where each original face's block starts
    pos = (first[sel][:, None] + torch.arange(4)[None]).flatten()
    out[pos] = kids.reshape(-1, 3)
    return SubdividedFaces(out, edges, int(n_verts), parent)


def midpoint_values(values: torch.Tensor, edges: torch.Tensor, unit: bool = False) -> torch.Tensor:
    """Append the edge midpoints' values to per-vertex values.

    Args:
        values: (..., V, C) per-vertex values (positions, normals, UVs, region weights).
        edges: (M, 2) int64 from :class:`SubdividedFaces`.
        unit: renormalise the midpoint values to unit length (normals).

    Returns:
        (..., V + M, C): the values, then the mean of each edge's two endpoints.
    """
    check_shape(edges, ["M", 2], name="edges")
    m = 0.5 * (values[..., edges[:, 0], :] + values[..., edges[:, 1], :])
    if unit:
        m = m / m.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    return torch.cat([values, m.to(values.dtype)], -2)
