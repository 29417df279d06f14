"""Homogeneous clipping of triangles against the near, far and guard-band planes.

Internal to :mod:`relightnet.raster.rasterize`. Triangles are clipped in clip space
(before the division by w), so a triangle with vertices behind the camera never
wraps around. Sutherland–Hodgman, vectorised over triangles with a fixed-size
polygon buffer (a triangle clipped by six planes has at most nine vertices).

Watertightness: the intersection of an edge with a plane is always computed from
the inside endpoint towards the outside one, so two triangles sharing an edge get
bit-identical clipped vertices.
"""

from __future__ import annotations

import torch

__all__ = ["GUARD_BAND", "plane_distances", "outcodes", "clip_triangles"]

#: Triangles are clipped to |x|, |y| <= GUARD_BAND * w (NDC within ±GUARD_BAND), which
#: keeps snapped pixel coordinates small enough for exact float64 edge functions.
GUARD_BAND = 2.0

_MAXV = 9


def plane_distances(clip: torch.Tensor) -> torch.Tensor:
    """(..., 4) clip-space points → (..., 10) signed distances, ``>= 0`` inside.

    Columns 0–5 are clipped against: near (z ≥ −w), far (z ≤ w), guard band
    (±x ≤ g·w, ±y ≤ g·w with g = GUARD_BAND). Columns 6–9 are the viewport sides
    (±x ≤ w, ±y ≤ w), used only to reject whole triangles. Written with elementwise
    operations only, so a point gets bit-identical distances wherever it appears.
    """
    x, y, z, w = clip.unbind(-1)
    gw = w * GUARD_BAND
    return torch.stack([z + w, w - z, gw - x, gw + x, gw - y, gw + y, w - x, w + x, w - y, w + y], dim=-1)


def outcodes(clip: torch.Tensor) -> torch.Tensor:
    """(..., 4) clip-space points → (...,) int64 bit set of the planes they are outside of."""
    bits = 2 ** torch.arange(10, device=clip.device)
    return ((plane_distances(clip) < 0).long() * bits).sum(-1)


def clip_triangles(tri: torch.Tensor, ids: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Clip triangles against planes 0–5 of :func:`plane_distances` and fan-triangulate.

    Args:
        tri: (M, 3, 4) float64 clip-space triangles.
        ids: (M,) int64 identifiers carried to the pieces.

    Returns:
        ``(pieces (M', 3, 4), ids (M',))``: triangles lying inside all six planes; each
        keeps the vertex order (orientation) of its source triangle.
    """
    M = tri.shape[0]
    dev = tri.device
    poly = torch.zeros(M, _MAXV, 4, dtype=tri.dtype, device=dev)
    poly[:, :3] = tri
    n = torch.full((M,), 3, dtype=torch.long, device=dev)
    slot = torch.arange(_MAXV, device=dev)
    for k in range(6):
        if M == 0:
            break
        d = plane_distances(poly)[..., k]
        valid = slot[None] < n[:, None]
        nxt = torch.where(slot[None] + 1 < n[:, None], slot[None] + 1, torch.zeros_like(slot[None]))
        pn = torch.gather(poly, 1, nxt[..., None].expand(-1, -1, 4))
        dn = torch.gather(d, 1, nxt)
        cin, nin = d >= 0, dn >= 0
        a = torch.where(cin[..., None], poly, pn)
        b = torch.where(cin[..., None], pn, poly)
        da = torch.where(cin, d, dn)
        db = torch.where(cin, dn, d)
        cross = valid & (cin != nin)
        t = torch.where(cross, da / torch.where(cross, da - db, torch.ones_like(da)), torch.zeros_like(da))
        inter = a + t[..., None] * (b - a)
        cand = torch.stack([poly, inter], dim=2).reshape(M, 2 * _MAXV, 4)
        keep = torch.stack([valid & cin, cross], dim=2).reshape(M, 2 * _MAXV)
        order = torch.argsort((~keep).to(torch.int8), dim=1, stable=True)[:, :_MAXV]
        poly = torch.gather(cand, 1, order[..., None].expand(-1, -1, 4))
        n = keep.sum(1)
        alive = n >= 3
        poly, n, ids = poly[alive], n[alive], ids[alive]
        M = poly.shape[0]
    # Fan triangulation (v0, v_j, v_j+1), j = 1 .. n-2.
    j = torch.arange(1, _MAXV - 1, device=dev)
    use = j[None] < (n[:, None] - 1)
    m_idx, j_idx = torch.nonzero(use, as_tuple=True)
    j_sel = j[j_idx]
    pieces = torch.stack([poly[m_idx, 0], poly[m_idx, j_sel], poly[m_idx, j_sel + 1]], dim=1)
    return pieces, ids[m_idx]
