"""Diffuse interreflection of per-vertex SH transport (Sloan et al. 2002; Green 2003).

Each occluded ray of vertex p that hits the *front* of a triangle at q brings
back the light that q reflects diffusely toward p:

    T^b_k(p) = Σ_rays w_d · max(n_p·ω_d, 0) · (ρ(q)/π) · T^{b−1}_k(q)

with ``T^0`` the shadowed transport and ``T = T^0 + T^1 + … + T^B``. ``T^{b−1}(q)``
and ``ρ(q)`` are interpolated from the hit triangle's vertices with the hit's
barycentrics, as the product ``Σ_j b_j ρ_j T_j`` (one linear map of the per-vertex
``ρ ⊙ T``). ``ρ`` is the albedo of the *reflector*: the receiver's own albedo is
applied at shading time (pixel = albedo ⊙ (T·L)), so T stays albedo-free at p.

Back-face hits (the ray meets a triangle from behind, i.e. from inside a closed
mesh or through the back of an open sheet) block the ray but reflect nothing.

All rays and their hits are gathered once into a sparse (V, V) matrix, the
:class:`BounceOperator`; every bounce is then one sparse matmul. With ρ < 1 the
series converges geometrically.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse
import torch

from ..checks import InputError, check_finite, check_shape
from .visibility import RayHits, VertexRays

__all__ = ["BounceOperator", "bounce_operator", "check_albedo", "interreflect"]


@dataclass(frozen=True)
class BounceOperator:
    """One diffuse bounce as a linear map of per-vertex transport.

    Attributes:
        matrix: (V, V) float32 sparse CSR; ``T^b = matrix @ (ρ ⊙ T^{b−1})``
            (ρ per vertex, applied per channel).
        n_rays: rays cast (upper hemisphere). n_blocked: rays that hit something.
        n_front: of those, hits on the front side of a triangle (the ones that reflect).
    """

    matrix: torch.Tensor
    n_rays: int
    n_blocked: int
    n_front: int


def bounce_operator(
    rays: VertexRays, hits: RayHits, faces: torch.Tensor, weights: torch.Tensor, verts: torch.Tensor
) -> BounceOperator:
    """Gather the hits of the vertex rays into a :class:`BounceOperator`.

    Args:
        rays: the vertex rays (:func:`relightnet.prt.visibility.vertex_rays`).
        hits: their closest hits (``engine.intersect(rays.origins, rays.dirs)``).
        faces: (F, 3) int64. weights: (D,) quadrature weights of the direction set.
        verts: (V, 3) float32 positions (for the facing test).
    """
    f = faces.numpy()
    v = verts.numpy()
    blocked = hits.prim >= 0
    idx = np.nonzero(blocked)[0]
    prim = hits.prim[idx]
    tri = v[f[prim]]  # (H, 3, 3)
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    front = np.einsum("hc,hc->h", fn, rays.dirs[idx]) < 0
    idx, prim = idx[front], prim[front]
    u, w2 = hits.u[idx], hits.v[idx]
    bary = np.stack([1 - u - w2, u, w2], axis=1).clip(0, 1)  # (H, 3)
    wd = weights.detach().cpu().numpy().astype(np.float32)
    scale = wd[rays.direction[idx]] * rays.cosine[idx] / np.float32(math.pi)
    rows = np.repeat(rays.vertex[idx], 3)
    cols = f[prim].reshape(-1)
    vals = (bary * scale[:, None]).reshape(-1).astype(np.float32)
    n = rays.n_verts
    csr = scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(n, n))  # sums duplicate (row, col)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*[Ss]parse.*")
        m = torch.sparse_csr_tensor(
            torch.from_numpy(csr.indptr.astype(np.int64)),
            torch.from_numpy(csr.indices.astype(np.int64)),
            torch.from_numpy(csr.data.astype(np.float32)),
            (n, n),
        )
    return BounceOperator(matrix=m, n_rays=len(hits.prim), n_blocked=int(blocked.sum()), n_front=len(idx))


def check_albedo(albedo, n_verts: int) -> torch.Tensor:
    """Albedo as a (V, C) float32 tensor, C = 1 (scalar or (V,) grey) or 3 ((V, 3) RGB).

    Raises:
        ShapeError: another shape. InputError: NaN or values outside [0, 1].
    """
    a = torch.as_tensor(albedo, dtype=torch.float32)
    if a.dim() == 0:
        a = a.expand(n_verts, 1)
    elif a.dim() == 1:
        check_shape(a, ["V"], name="albedo", dims={"V": n_verts})
        a = a[:, None]
    else:
        check_shape(a, ["V", 3], name="albedo", dims={"V": n_verts})
    check_finite(a, "albedo")
    if a.numel() and (a.min() < 0 or a.max() > 1):
        raise InputError(f"albedo: expected values in [0, 1], got range [{a.min():.3g}, {a.max():.3g}]")
    return a.contiguous()


def interreflect(T0: torch.Tensor, op: BounceOperator, albedo: torch.Tensor, bounces: int) -> torch.Tensor:
    """Add ``bounces`` diffuse bounces to a direct transport.

    Args:
        T0: (V, K) shadowed transport. op: the mesh's :class:`BounceOperator`.
        albedo: (V, C) from :func:`check_albedo` (C = 1 or 3).
        bounces: number of bounces ≥ 0.

    Returns:
        (V, K) when C = 1, (V, K, 3) when C = 3: ``Σ_{b=0..B} T^b``.
    """
    check_shape(T0, ["V", "K"], name="T0")
    check_shape(albedo, ["V", "C"], name="albedo", dims={"V": T0.shape[0]})
    if int(bounces) != bounces or bounces < 0:
        raise InputError(f"bounces: expected an integer >= 0, got {bounces!r}")
    n, k = T0.shape
    c = albedo.shape[1]
    prev = T0[:, :, None].expand(n, k, c).contiguous()
    total = prev.clone()
    for _ in range(int(bounces)):
        prev = (op.matrix @ (prev * albedo[:, None, :]).reshape(n, k * c)).reshape(n, k, c)
        total += prev
    return total[:, :, 0] if c == 1 else total
