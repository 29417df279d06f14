"""Analytic edge antialiasing of rasterized images (a simplified nvdiffrast ``antialias``).

For every pair of horizontally or vertically adjacent pixels A, B showing different
triangles (or a triangle and background), the boundary between them is located
analytically: the segment between the pixel centres is intersected with the edges of
the triangle that is in front at the boundary (the triangle of A if, extended to B, it
would be nearer than what B shows; otherwise the triangle of B). If the boundary
crosses at fraction s of the way from A to B, the pixel on the far side of the midpoint
receives the other pixel's colour with weight |s − 0.5| (the 1D coverage of that pixel
by the other surface). Pixel pairs whose two triangles share an edge (two vertex indices)
are interior to a surface and left alone, as are pairs involving triangles with a vertex
behind the camera.

The result is differentiable w.r.t. ``color`` and, through the crossing positions, w.r.t.
``verts_clip`` (silhouette gradients).
"""

from __future__ import annotations

import torch

from ..checks import check_shape
from .fragments import Fragments

__all__ = ["antialias", "silhouette_pixels"]


def _lam(P, u, v):
    """Screen-space barycentrics (N, 3) at NDC (u, v) of triangles with NDC vertices P (N, 3, 2)."""
    d1, d2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    det = torch.where(det == 0, torch.full_like(det, 1e-30), det)
    du, dv = u - P[:, 0, 0], v - P[:, 0, 1]
    l1 = (du * d2[:, 1] - dv * d2[:, 0]) / det
    l2 = (dv * d1[:, 0] - du * d1[:, 1]) / det
    return torch.stack([1 - l1 - l2, l1, l2], dim=1)


def _exit(lam_a, lam_b):
    """Fraction along A→B where the segment leaves a triangle containing A (1 if it does not)."""
    out = lam_b < 0
    s = lam_a / torch.where(out, lam_a - lam_b, torch.ones_like(lam_a))
    s = torch.where(out, s.clamp(0, 1), torch.ones_like(s))
    return s.min(dim=1).values


def antialias(color: torch.Tensor, frags: Fragments, verts_clip: torch.Tensor, faces: torch.Tensor) -> torch.Tensor:
    """Blend colours across triangle boundaries according to where the edges cross.

    Args:
        color: (B, H, W, C) shaded image (background included) from the same rasterization.
        frags: :class:`Fragments` of ``rasterize(verts_clip, faces, ...)``.
        verts_clip: (B, V, 4) clip-space vertices that were rasterized.
        faces: (F, 3).

    Returns:
        (B, H, W, C) antialiased image.
    """
    B, H, W = frags.shape
    check_shape(color, [B, H, W, "C"], name="color")
    check_shape(verts_clip, [B, "V", 4], name="verts_clip")
    C = color.shape[-1]
    V = verts_clip.shape[1]
    fid = frags.face_id
    depth = frags.depth.reshape(-1)
    flat = color.reshape(-1, C)
    faces = faces.to(device=color.device, dtype=torch.long)
    out = flat.clone()
    idx = torch.arange(B * H * W, device=color.device).view(B, H, W)
    for a, b in ((idx[:, :, :-1], idx[:, :, 1:]), (idx[:, :-1, :], idx[:, 1:, :])):
        fa, fb = fid.reshape(-1)[a.reshape(-1)], fid.reshape(-1)[b.reshape(-1)]
        diff = torch.nonzero(fa != fb).squeeze(1)
        if diff.numel() == 0:
            continue
        pa, pb = a.reshape(-1)[diff], b.reshape(-1)[diff]
        fa, fb = fa[diff], fb[diff]
        s = _crossing(pa, pb, fa, fb, depth, verts_clip, faces, V, H, W)
        ok = torch.isfinite(s)
        s = torch.where(ok, s, torch.full_like(s, 0.5)).to(color.dtype)[:, None]
        ca, cb = flat[pa], flat[pb]
        out = out.index_add(0, pb, (s - 0.5).clamp(min=0) * (ca - cb))
        out = out.index_add(0, pa, (0.5 - s).clamp(min=0) * (cb - ca))
    return out.view(B, H, W, C)


def _crossing(pa, pb, fa, fb, depth, verts_clip, faces, V, H, W):
    """Boundary position (fraction from A to B) for pixel pairs; NaN where none is found."""
    HW = H * W
    bidx = torch.div(pa, HW, rounding_mode="floor")

    def ndc(p):
        r = p - bidx * HW
        y = torch.div(r, W, rounding_mode="floor")
        x = r - y * W
        return (2 * x + 1).to(verts_clip.dtype) / W - 1, 1 - (2 * y + 1).to(verts_clip.dtype) / H

    ua, va = ndc(pa)
    ub, vb = ndc(pb)
    nan = torch.full_like(ua, float("nan"))

    def tri(f):
        """NDC vertices (N, 3, 2), depths (N, 3), usable mask of the triangles f (−1 = none)."""
        fc = f.clamp(min=0)
        vc = verts_clip.reshape(-1, 4)[(faces[fc] + (bidx * V)[:, None]).reshape(-1)].view(-1, 3, 4)
        w = vc[..., 3]
        usable = (f >= 0) & (w > 0).all(1)
        w = torch.where(w > 0, w, torch.ones_like(w))
        return vc[..., :2] / w[..., None], vc[..., 2] / w, usable

    fva, fvb = faces[fa.clamp(min=0)], faces[fb.clamp(min=0)]
    shared = (fva[:, :, None] == fvb[:, None, :]).sum((1, 2))
    interior = (fa >= 0) & (fb >= 0) & (shared >= 2)
    Pa, za, oka = tri(fa)
    Pb, zb, okb = tri(fb)
    la_a, la_b = _lam(Pa, ua, va), _lam(Pa, ub, vb)
    lb_b, lb_a = _lam(Pb, ub, vb), _lam(Pb, ua, va)
    sa = _exit(la_a, la_b)  # leaving A's triangle towards B
    sb = _exit(lb_b, lb_a)  # leaving B's triangle towards A
    da, db = depth[pa], depth[pb]
    a_front = oka & (sa < 1) & ((fb < 0) | ((la_b * za).sum(1) <= db))
    b_front = okb & (sb < 1) & ((fa < 0) | ((lb_a * zb).sum(1) <= da))
    return torch.where(interior, nan, torch.where(a_front, sa, torch.where(b_front, 1 - sb, nan)))


def silhouette_pixels(mask: torch.Tensor) -> torch.Tensor:
    """(H, W) bool: pixels with a 4-neighbour on the other side of the mask's boundary.

    Where only the silhouette should be smoothed (an object composited over a photo), take
    :func:`antialias`'s result at these pixels only: between two triangles that share no edge
    it also blends inside the object (with pixel-sized triangles, nearly everywhere).

    Args:
        mask: (H, W) bool or {0, 1}.
    """
    check_shape(mask, ["H", "W"], name="mask")
    p = torch.nn.functional.pad(mask[None, None].float(), (1, 1, 1, 1), mode="replicate")[0, 0]
    nb = torch.stack([p[:-2, 1:-1], p[2:, 1:-1], p[1:-1, :-2], p[1:-1, 2:]])
    return (nb != mask.float()).any(0)
