"""Texels never seen, filled: the body's mirror image first, then the mesh around them.

1. **Symmetry.** A person is nearly left/right symmetric, and a camera that saw one side of a
   body part often missed the other. Each island texel's mirror is the island texel nearest to
   its rest position reflected in the body's sagittal plane (x → −x: Anny's rest pose is symmetric
   about x = 0 to a third of a millimetre; within
   :data:`MIRROR_RADIUS`); an unseen texel whose mirror was seen takes its colour.
2. **Inpainting over the mesh.** What is still unseen (the soles, the top of the head, a back
   never turned to the camera) takes the colour that diffuses over the mesh's edges from the
   seen vertices around it — first only along edges within the same body part (an unseen hand
   fills from the hand, not from the sleeve), then along any edge for parts never seen at all —
   interpolated at the texel's barycentrics. It works on the mesh, not in UV space, so it crosses
   the seams between UV islands.
"""

from __future__ import annotations

import numpy as np
import torch

from ..checks import check_shape

__all__ = ["MIRROR_RADIUS", "mirror_texels", "fill_unseen"]

#: Metres within which a reflected texel must find an island texel to be its mirror.
MIRROR_RADIUS = 0.01


def mirror_texels(rest_pos: np.ndarray) -> np.ndarray:
    """(M,) index of each texel's mirror image (−1 where none lies within :data:`MIRROR_RADIUS`).

    Args:
        rest_pos: (M, 3) rest-pose positions of the island texels (x across the body).
    """
    from scipy.spatial import cKDTree

    check_shape(rest_pos, ["M", 3], name="rest_pos")
    mirrored = rest_pos.copy()
    mirrored[:, 0] = -mirrored[:, 0]
    dist, idx = cKDTree(rest_pos).query(mirrored, distance_upper_bound=MIRROR_RADIUS)
    return np.where(np.isfinite(dist), idx, -1).astype(np.int64)


def _edges(faces: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    e = torch.cat([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    e = torch.cat([e, e.flip(1)]).unique(dim=0)
    return e[:, 0], e[:, 1]


def _diffuse(colour: torch.Tensor, known: torch.Tensor, src: torch.Tensor, dst: torch.Tensor,
             iters: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Grow ``colour`` (V, 3) from the ``known`` (V,) vertices along the edges src → dst, one ring a step,
    each new vertex the mean of its known neighbours; returns (colour, known)."""
    colour, known = colour.clone(), known.clone()
    V = colour.shape[0]
    for _ in range(iters):
        ok = known[src] & ~known[dst]
        if not bool(ok.any()):
            break
        acc = torch.zeros(V, 3).index_add_(0, dst[ok], colour[src[ok]])
        cnt = torch.zeros(V).index_add_(0, dst[ok], torch.ones(int(ok.sum())))
        new = cnt > 0
        colour[new] = acc[new] / cnt[new, None]
        known = known | new
    return colour, known


def fill_unseen(values: torch.Tensor, seen: torch.Tensor, tri: torch.Tensor, bary: torch.Tensor,
                mirror: torch.Tensor, faces: torch.Tensor, parts: torch.Tensor, n_verts: int
                ) -> tuple[torch.Tensor, torch.Tensor]:
    """Fill the unseen island texels (module docstring).

    Args:
        values: (M, 3) fused texel colours. seen: (M,) bool.
        tri: (M, 3) int64 and bary: (M, 3) each texel's triangle and barycentrics.
        mirror: (M,) int64 :func:`mirror_texels`. faces: (F, 3) int64. parts: (V,) int64 body part per vertex.
        n_verts: V.

    Returns:
        ``(filled (M, 3), how (M,) int8)``: 0 seen, 1 from the mirror, 2 inpainted over the mesh.
    """
    d = check_shape(values, ["M", 3], name="values")
    for x, name in ((seen, "seen"), (mirror, "mirror")):
        check_shape(x, [d["M"]], name=name)
    out = values.clone()
    how = torch.where(seen, 0, 2).to(torch.int8)
    cand = torch.nonzero(~seen & (mirror >= 0)).squeeze(1)
    cand = cand[seen[mirror[cand]]]
    out[cand] = values[mirror[cand]]
    how[cand] = 1
    have = seen.clone()
    have[cand] = True
    # Vertex colours from the texels that have one, weighted by their barycentrics.
    w = bary[have].reshape(-1)
    vid = tri[have].reshape(-1)
    acc = torch.zeros(n_verts, 3).index_add_(0, vid, out[have].repeat_interleave(3, 0) * w[:, None])
    wsum = torch.zeros(n_verts).index_add_(0, vid, w)
    known = wsum > 1e-3
    colour = torch.where(known[:, None], acc / wsum.clamp_min(1e-6)[:, None], torch.zeros(()))
    src, dst = _edges(faces)
    same = parts[src] == parts[dst]
    colour, known = _diffuse(colour, known, src[same], dst[same], n_verts)
    colour, known = _diffuse(colour, known, src, dst, n_verts)
    rest = ~have
    out[rest] = torch.einsum("mk,mkc->mc", bary[rest], colour[tri[rest]])
    return out, how
