"""Per-vertex transport of a once-subdivided mesh, ray casting the midpoints only at shadow edges.

A mesh subdivided once (:func:`relightnet.body.subdivide.subdivide_faces`) has a vertex at the midpoint
m of every split edge a–b. Casting all of their rays would cost as much as the rest of
the mesh again; instead :func:`refined_transport` casts the rays of the original vertices,
then, per midpoint, compares the visibility of its two endpoints over the directions both
see above their horizon, weighted by the midpoint's own cosine:

    d(m) = Σ_ω |V_a(ω) − V_b(ω)| · max(n_m·ω, 0) / Σ_ω max(n_m·ω, 0)

Where ``d > threshold`` a shadow boundary crosses the edge (a *shadow edge*) and the
midpoint is ray cast like any vertex: its row equals :func:`~relightnet.prt.vertex_transport`'s.
Elsewhere its visibility is the mean of its endpoints' (the one endpoint above its horizon
where only one is; visible where neither is) and its transport is that visibility times
its own cosine lobe, projected like every row: ``T_m = (V̂_m ⊙ max(n_m·ω, 0)) @ (Y ⊙ w)``.
Both are exact where the endpoints agree (no shadow in between); only the interpolated
visibility of edges with a small disagreement is an estimate.

Every row is projected by one product over all V rows (a BLAS sums a row in an order that depends
on its place in the matrix), so a vertex's row does not depend on which vertices are wanted.

Interreflection (``bounces ≥ 1``): the bounce operator gathers the rays of every cast vertex;
a midpoint that was not cast takes the mean of its endpoints' bounced transport.

Shapes: V vertices (midpoints included), F faces, M midpoints, K = (lmax + 1)² coefficients.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

from ..checks import InputError, check_shape
from ..sh import light_to_world, sh_basis, sh_count
from .interreflection import bounce_operator, check_albedo
from .mesh_checks import check_mesh, check_normals, mesh_scale
from .settings import PrtSettings
from .transport import cast_lit, transport_directions
from .visibility import RayEngine, VertexRays, make_engine, vertex_rays

__all__ = ["SHADOW_EDGE", "refined_transport"]

#: Default ``threshold`` of :func:`refined_transport`: the cosine-weighted share of directions
#: in which the endpoints' visibility differs above which a midpoint is ray cast.
SHADOW_EDGE = 0.08


def _check_midpoints(midpoints, n: int) -> torch.Tensor:
    mid = torch.as_tensor(midpoints, dtype=torch.int64)
    check_shape(mid, ["M", 3], name="midpoints")
    if mid.numel() == 0:
        return mid
    if int(mid.min()) < 0 or int(mid.max()) >= n:
        raise InputError(f"midpoints: expected vertex indices in [0, {n}), got [{int(mid.min())}, {int(mid.max())}]")
    is_mid = torch.zeros(n, dtype=torch.bool)
    is_mid[mid[:, 0]] = True
    if int(is_mid.sum()) != mid.shape[0] or bool(is_mid[mid[:, 1:]].any()):
        raise InputError("midpoints: expected distinct midpoint vertices whose endpoints are not midpoints")
    return mid


def _cast(eng: RayEngine, idx: torch.Tensor, verts, normals, dirs, cos, offset: float, scale: float, hits: bool,
          lit: np.ndarray):
    """Cast the rays of the vertices ``idx`` into their rows of ``lit`` (V, D) (the cosine where visible,
    0 elsewhere; ``cos`` (V, D) is n·ω of every vertex): (rays with global vertex ids, their hits or None)."""
    rays = vertex_rays(verts[idx], normals[idx], dirs, offset, scale=scale, cosines=cos[idx])
    rays = dataclasses.replace(rays, vertex=idx.numpy()[rays.vertex], n_verts=verts.shape[0])
    lit[idx.numpy()] = 0.0
    _, h = cast_lit(eng, rays, hits, out=lit)
    return rays, h


def _estimate(lit_a, lit_b, cos_a, cos_b, cos_m, threshold: float):
    """Endpoint visibilities (N, D) → (midpoint lit (N, D) estimate, shadow edge (N,) bool).

    ``lit`` is 0 below an endpoint's horizon, so with k = [cos > 0] the estimate (both above: the
    mean; one: its own; neither: visible) is (V_a + V_b) / max(k_a + k_b, 1) + [k_a + k_b = 0]."""
    va, vb = (lit_a > 0).float(), (lit_b > 0).float()
    ka, kb = (cos_a > 0).float(), (cos_b > 0).float()
    k = ka + kb
    d = ((va - vb).abs() * ka * kb * cos_m).sum(1) / cos_m.sum(1).clamp_min(1e-12)
    vis = (va + vb) / k.clamp_min(1.0) + (k == 0).float()
    return vis * cos_m, d > threshold


def _midpoint_rows(lit: torch.Tensor, cos: torch.Tensor, wm: torch.Tensor, threshold: float,
                   chunk: int = 4096) -> torch.Tensor:
    """Write the estimated visibility-times-cosine rows of the midpoints ``wm`` (E, 3) into ``lit`` (V, D)
    from their endpoints' rows (``cos`` (V, D): n·ω of every vertex); returns (E,) bool, the shadow edges
    (whose rows are to be cast)."""
    shadow = torch.zeros(len(wm), dtype=torch.bool)
    for s in range(0, len(wm), chunk):
        w = wm[s:s + chunk]
        est, shadow[s:s + chunk] = _estimate(lit[w[:, 1]], lit[w[:, 2]], cos[w[:, 1]], cos[w[:, 2]],
                                             cos[w[:, 0]].clamp_min(0), threshold)
        lit[w[:, 0]] = est
    return shadow


def _rows(want: torch.Tensor, is_mid: torch.Tensor, mid: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """(original vertices to cast, midpoint rows wanted) for the wanted vertices (V,) bool."""
    need = want & ~is_mid
    wm = mid[want[mid[:, 0]]]
    need[wm[:, 1:].flatten()] = True
    return torch.nonzero(need).flatten(), wm


def _bounce(T0, rays: list[VertexRays], hits: list, faces, weights, verts, rho, bounces: int, est_mid):
    """T0 (V, K) plus ``bounces`` bounces; midpoint rows ``est_mid`` (E, 3) take their endpoints' mean."""
    rays_all = VertexRays(*(np.concatenate([getattr(r, f) for r in rays]) for f in
                            ("vertex", "direction", "origins", "dirs", "cosine")), verts.shape[0], rays[0].n_dirs)
    hits_all = type(hits[0])(*(np.concatenate([getattr(h, f) for h in hits]) for f in ("prim", "u", "v", "t")))
    op = bounce_operator(rays_all, hits_all, faces, weights, verts)
    n, k = T0.shape
    c = rho.shape[1]
    prev = T0[:, :, None].expand(n, k, c).contiguous()
    total = prev.clone()
    for _ in range(int(bounces)):
        prev = (op.matrix @ (prev * rho[:, None, :]).reshape(n, k * c)).reshape(n, k, c)
        prev[est_mid[:, 0]] = 0.5 * (prev[est_mid[:, 1]] + prev[est_mid[:, 2]])
        total += prev
    return total[:, :, 0] if c == 1 else total


def refined_transport(verts, faces, normals, midpoints, lmax: int = 2, prt: PrtSettings = PrtSettings(),
                      albedo=None, vertices=None, manifold: str = "warn", threshold: float = SHADOW_EDGE,
                      return_cast: bool = False):
    """Per-vertex SH transport (occluded) of a subdivided mesh, midpoints ray cast only at shadow edges.

    Args:
        verts: (V, 3), faces: (F, 3), normals: (V, 3) as for :func:`~relightnet.prt.vertex_transport`.
        midpoints: (M, 3) int64 rows (midpoint vertex m, endpoint a, endpoint b): m lies on edge a–b
            (:attr:`relightnet.body.subdivide.SubdividedFaces.midpoints`); endpoints are not midpoints.
        lmax, prt, albedo, manifold: as for ``vertex_transport``; ``prt`` (a
            :class:`~relightnet.prt.PrtSettings`) with ``occlusion`` (every vertex is ray cast here).
        vertices: (N,) indices of the only rows wanted (others 0); not with ``bounces``. The rows
            wanted equal those of the full computation bit for bit.
        threshold: the endpoints' visibility difference ``d`` above which a midpoint is ray cast
            (module docstring); 0 casts every midpoint whose endpoints differ at all.
        return_cast: also return which midpoints were ray cast.

    Returns:
        (V, K) float32 (or (V, K, 3) with bounces and RGB albedo); with ``return_cast`` also
        (M,) bool, True for the midpoints that were ray cast (False for those not wanted).
    """
    sh_count(lmax)
    if not isinstance(prt, PrtSettings) or not prt.occlusion:
        raise InputError(f"prt: expected PrtSettings with occlusion=True (refined transport casts rays), got {prt!r}")
    bounces = prt.bounces
    if not 0 <= threshold <= 1:
        raise InputError(f"threshold: expected a value in [0, 1], got {threshold!r}")
    verts, faces = check_mesh(verts, faces, manifold=manifold)
    nv = verts.shape[0]
    normals = check_normals(normals, nv)
    mid = _check_midpoints(midpoints, nv)
    rho = check_albedo(0.5 if albedo is None else albedo, nv) if bounces else None
    want = torch.ones(nv, dtype=torch.bool)
    if vertices is not None:
        if bounces:
            raise InputError("vertices: a vertex subset cannot be used with bounces (they need every vertex)")
        idx = torch.as_tensor(vertices, dtype=torch.int64).flatten()
        if idx.numel() and (int(idx.min()) < 0 or int(idx.max()) >= nv):
            raise InputError(f"vertices: expected indices in [0, {nv}), got [{int(idx.min())}, {int(idx.max())}]")
        want = torch.zeros(nv, dtype=torch.bool)
        want[idx] = True
    is_mid = torch.zeros(nv, dtype=torch.bool)
    is_mid[mid[:, 0]] = True
    dirs_light, weights = transport_directions(prt.n_dirs, prt.seed)
    dirs = light_to_world(dirs_light)
    Yw = sh_basis(dirs_light, lmax, check=False) * weights[:, None]
    eng = make_engine(verts, faces, prt.engine, prt.threads)
    scale = mesh_scale(verts)
    cast_v, wm = _rows(want, is_mid, mid)
    # Every row of n·ω and of the projection below is one product over the whole mesh: BLAS sums a row in
    # an order that depends on its place in the matrix, so this keeps a vertex's row independent of
    # which vertices are wanted (a subset's rows equal the full computation's, bit for bit).
    cos = normals @ dirs.T
    lit = np.zeros((nv, dirs.shape[0]), dtype=np.float32)  # visibility × cosine of every row wanted
    rays, hits = _cast(eng, cast_v, verts, normals, dirs, cos, prt.offset, scale, bool(bounces), lit)
    shadow = _midpoint_rows(torch.from_numpy(lit), cos, wm, float(threshold))
    all_rays, all_hits = [rays], [hits]
    if bool(shadow.any()):
        rays_m, hits_m = _cast(eng, wm[shadow, 0], verts, normals, dirs, cos, prt.offset, scale, bool(bounces), lit)
        all_rays.append(rays_m)
        all_hits.append(hits_m)
    T = torch.from_numpy(lit) @ Yw
    if vertices is not None:
        T[~want] = 0.0  # endpoints cast only for their midpoints
    if bounces:
        T = _bounce(T, all_rays, all_hits, faces, weights, verts, rho, int(bounces), wm[~shadow])
    if not return_cast:
        return T
    cast = torch.zeros(mid.shape[0], dtype=torch.bool)
    row = torch.full((nv,), -1, dtype=torch.int64)
    row[mid[:, 0]] = torch.arange(mid.shape[0])
    cast[row[wm[shadow, 0]]] = True
    return T, cast
