"""Per-vertex precomputed radiance transfer (PRT) in the SH basis.

``T_k(p) = ∫ V(p, ω) · max(n·ω, 0) · Y_k(ω) dω`` (no 1/π; docs/design.md, "Transport and shading"), with ω in
the light frame. All vertices share one direction set (a spherical Fibonacci
lattice, randomly rotated for a given seed), so the projection is one matmul:
``T = (V ⊙ max(n·ω, 0)) @ (Y(ω) ⊙ w)``. Without occlusion this converges to the
closed form ``Â_l Y_k(n)`` (error ≈ 5e-4 at 1024 directions, ≈ 3e-3 at 256).

Interreflection (``bounces ≥ 1``) is added by :mod:`relightnet.prt.interreflection`.
"""

from __future__ import annotations

import numpy as np
import torch

from ..checks import InputError
from ..sh import fibonacci_sphere, light_to_world, sh_basis, sh_count
from ..sh.directions import random_fibonacci_sphere
from .interreflection import bounce_operator, check_albedo, interreflect
from .mesh_checks import check_mesh, check_normals, mesh_scale
from .settings import PrtSettings
from .visibility import make_engine, vertex_rays

__all__ = ["transport_directions", "vertex_transport"]


def transport_directions(n_dirs: int = 256, seed: int | None = 0) -> tuple[torch.Tensor, torch.Tensor]:
    """The shared direction set of :func:`vertex_transport`.

    Args:
        n_dirs: number of directions D.
        seed: a uniformly random rotation of the Fibonacci lattice drawn from this
            seed (deterministic); ``None`` keeps the plain lattice.

    Returns:
        dirs: (D, 3) float32 unit directions in the *light* frame; weights: (D,) float32, summing to 4π.
    """
    if int(n_dirs) != n_dirs or n_dirs < 1:
        raise InputError(f"n_dirs: expected a positive integer, got {n_dirs!r}")
    if seed is None:
        return fibonacci_sphere(int(n_dirs))
    return random_fibonacci_sphere(int(n_dirs), generator=torch.Generator().manual_seed(int(seed)))


def _vertex_subset(vertices, n: int, bounces: int) -> torch.Tensor | None:
    if vertices is None:
        return None
    if bounces:
        raise InputError("vertices: a vertex subset cannot be used with bounces (they need every vertex)")
    idx = torch.as_tensor(vertices, dtype=torch.int64).flatten()
    if idx.numel() and (int(idx.min()) < 0 or int(idx.max()) >= n):
        raise InputError(f"vertices: expected indices in [0, {n}), got [{int(idx.min())}, {int(idx.max())}]")
    return idx


def cast_lit(eng, rays, with_hits: bool, out: np.ndarray | None = None):
    """Cast ``rays`` (:class:`~relightnet.prt.visibility.VertexRays`) with ``eng``: (lit (N, D) float32, the ray's
    cosine where it escapes and 0 where it is blocked; the hits, when ``with_hits``, else None).

    ``out``: a C-contiguous (N, D) float32 array to write the rays' entries into (and return) instead
    of a new zero array; its other entries are left as they are."""
    if with_hits:
        hits = eng.intersect(rays.origins, rays.dirs)
        blocked = hits.prim >= 0
    else:
        hits, blocked = None, eng.occluded(rays.origins, rays.dirs)
    if out is None:
        lit = np.zeros((rays.n_verts, rays.n_dirs), dtype=np.float32)
    else:
        lit = out
        if lit.shape != (rays.n_verts, rays.n_dirs) or lit.dtype != np.float32 or not lit.flags.c_contiguous:
            raise InputError(f"out: expected a C-contiguous ({rays.n_verts}, {rays.n_dirs}) float32 array")
    lit.reshape(-1)[rays.vertex * rays.n_dirs + rays.direction] = np.where(blocked, np.float32(0.0), rays.cosine)
    return lit, hits


def vertex_transport(
    verts,
    faces,
    normals,
    lmax: int = 2,
    prt: PrtSettings = PrtSettings(),
    albedo=None,
    vertices: torch.Tensor | None = None,
    manifold: str = "warn",
) -> torch.Tensor:
    """Per-vertex SH transport vectors of a mesh, with shadows and interreflections.

    Args:
        verts: (V, 3) world-frame positions (y up). faces: (F, 3) vertex indices,
            counter-clockwise seen from outside (that side is the front).
        normals: (V, 3) unit world-frame normals.
        lmax: SH order (K = (lmax+1)²).
        prt: a :class:`~relightnet.prt.PrtSettings`: the directions D of the shared quadrature
            set, occlusion (cast rays, or the unshadowed cosine lobe), interreflection bounces,
            the direction set's seed, the ray engine, origin offset and threads.
        albedo: diffuse albedo in [0, 1] of the reflecting surfaces for
            ``bounces ≥ 1``: a float, (V,) grey, or (V, 3) RGB. None means 0.5 grey.
            The receiver's own albedo is *not* in T (pixel = albedo ⊙ (T·L)).
        vertices: (M,) indices of the only vertices whose transport is wanted (e.g. those of
            the faces a camera sees); the others get 0. Rays still hit the whole mesh, so the
            wanted rows equal those of the full computation. Not with ``bounces``, which
            needs every vertex; ignored without ``occlusion`` (every row is cheap then).
        manifold: what to do with non-manifold edges (:func:`~relightnet.prt.check_mesh`); a
            caller that renders one topology in many poses checks it once and passes ``"ignore"``.

    Returns:
        (V, K) float32 transport, or (V, K, 3) when ``bounces ≥ 1`` and the
        albedo is RGB (V, 3): bounced light takes the colour of what it hits.
    """
    if not isinstance(prt, PrtSettings):
        raise InputError(f"prt: expected a PrtSettings, got {type(prt).__name__}")
    bounces = prt.bounces
    sh_count(lmax)
    verts, faces = check_mesh(verts, faces, manifold=manifold)
    normals = check_normals(normals, verts.shape[0])
    rho = check_albedo(0.5 if albedo is None else albedo, verts.shape[0]) if bounces else None
    dirs_light, weights = transport_directions(prt.n_dirs, prt.seed)
    dirs_world = light_to_world(dirs_light)
    Yw = sh_basis(dirs_light, lmax, check=False) * weights[:, None]  # (D, K)
    idx = _vertex_subset(vertices, verts.shape[0], bounces)
    if not prt.occlusion:  # cheap: every vertex
        cos = (normals @ dirs_world.T).clamp_min(0)
        return (cos @ Yw).contiguous()
    if idx is not None and idx.numel() == 0:
        return torch.zeros(verts.shape[0], Yw.shape[1])
    sub_v, sub_n = (verts, normals) if idx is None else (verts[idx], normals[idx])
    rays = vertex_rays(sub_v, sub_n, dirs_world, prt.offset, scale=mesh_scale(verts))
    eng = make_engine(verts, faces, prt.engine, prt.threads)
    lit, hits = cast_lit(eng, rays, bool(bounces))
    T = torch.from_numpy(lit) @ Yw
    if idx is not None:
        return torch.zeros(verts.shape[0], T.shape[1]).index_copy_(0, idx, T)
    if not bounces:
        return T
    op = bounce_operator(rays, hits, faces, weights, verts)
    return interreflect(T, op, rho, bounces)
