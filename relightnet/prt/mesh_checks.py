"""Validation of triangle meshes for ray casting.

Bad meshes fail early with :class:`~relightnet.checks.ShapeError` /
:class:`~relightnet.checks.InputError`: an empty mesh, faces indexing outside the
vertex array, NaN/Inf coordinates, normals that are not unit length, a mesh whose
vertices all coincide.

Non-manifold meshes (an edge shared by more than two faces) and open meshes
(boundary edges) are *accepted*: ray casting needs no topology, and light that
leaks through a hole is physically what an open surface does. A non-manifold edge
often means duplicated or overlapping faces, so :func:`check_mesh` reports it
with a :class:`MeshWarning` (``manifold="warn"``, the default), raises
(``manifold="error"``) or stays silent (``manifold="ignore"``).
"""

from __future__ import annotations

import warnings

import torch

from ..checks import InputError, ShapeError, check_finite, check_shape, check_unit

__all__ = ["MeshWarning", "check_mesh", "check_normals", "mesh_scale", "nonmanifold_edge_count"]


class MeshWarning(UserWarning):
    """A mesh is usable but suspicious (non-manifold edges)."""


def nonmanifold_edge_count(faces: torch.Tensor) -> int:
    """Number of undirected edges shared by more than two faces.

    Args:
        faces: (F, 3) int64 vertex indices.
    """
    e = torch.cat([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]).sort(dim=1).values
    key = e[:, 0] * (int(faces.max()) + 1) + e[:, 1]
    _, counts = torch.unique(key, return_counts=True)
    return int((counts > 2).sum())


def check_mesh(verts, faces, manifold: str = "warn") -> tuple[torch.Tensor, torch.Tensor]:
    """Validate a triangle mesh and return it as (float32 verts, int64 faces) CPU tensors.

    Args:
        verts: (V, 3) float vertex positions (tensor or array).
        faces: (F, 3) integer vertex indices, 0 ≤ index < V.
        manifold: what to do with edges shared by > 2 faces: ``"warn"``, ``"error"``, ``"ignore"``.

    Returns:
        verts (V, 3) float32, faces (F, 3) int64.

    Raises:
        ShapeError: wrong shapes. InputError: empty mesh, NaN/Inf, out-of-range
        indices, non-integer faces, all vertices coincident, non-manifold with ``manifold="error"``.
    """
    if manifold not in ("warn", "error", "ignore"):
        raise ValueError(f"manifold: expected 'warn', 'error' or 'ignore', got {manifold!r}")
    verts = torch.as_tensor(verts)
    faces = torch.as_tensor(faces)
    check_shape(verts, ["V", 3], name="verts")
    check_shape(faces, ["F", 3], name="faces")
    if verts.shape[0] == 0 or faces.shape[0] == 0:
        raise InputError(f"mesh is empty: {verts.shape[0]} vertices, {faces.shape[0]} faces")
    if not verts.is_floating_point():
        raise InputError(f"verts: expected a floating dtype, got {verts.dtype}")
    if faces.is_floating_point() or faces.dtype == torch.bool or faces.is_complex():
        raise InputError(f"faces: expected an integer dtype, got {faces.dtype}")
    check_finite(verts, "verts")
    faces = faces.detach().cpu().to(torch.int64)
    lo, hi = int(faces.min()), int(faces.max())
    if lo < 0 or hi >= verts.shape[0]:
        raise InputError(f"faces: indices must lie in [0, {verts.shape[0] - 1}], found range [{lo}, {hi}]")
    verts = verts.detach().cpu().to(torch.float32).contiguous()
    mesh_scale(verts)
    if manifold != "ignore":
        bad = nonmanifold_edge_count(faces)
        if bad:
            msg = f"mesh is non-manifold: {bad} edges are shared by more than two faces (duplicated faces?)"
            if manifold == "error":
                raise InputError(msg)
            warnings.warn(msg + "; ray casting proceeds", MeshWarning, stacklevel=3)
    return verts, faces.contiguous()


def check_normals(normals, n_verts: int, atol: float = 1e-3) -> torch.Tensor:
    """Validate per-vertex unit normals and return them as (V, 3) float32.

    Raises:
        ShapeError: not (V, 3) with the mesh's V. InputError: NaN or non-unit vectors.
    """
    normals = torch.as_tensor(normals)
    check_shape(normals, ["V", 3], name="normals", dims={"V": n_verts})
    if not normals.is_floating_point():
        raise InputError(f"normals: expected a floating dtype, got {normals.dtype}")
    check_unit(normals, name="normals", atol=atol)
    return normals.detach().cpu().to(torch.float32).contiguous()


def mesh_scale(verts: torch.Tensor) -> float:
    """Diagonal of the axis-aligned bounding box, the length unit of ray offsets.

    Raises:
        InputError: the diagonal is zero (every vertex at the same point).
    """
    if verts.shape[0] == 0:
        raise ShapeError("verts: expected at least one vertex")
    diag = float((verts.max(0).values - verts.min(0).values).norm())
    if not diag > 0:
        raise InputError("verts: all vertices coincide, the mesh has no extent")
    return diag
