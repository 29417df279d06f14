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

__all__ = ["antialias", "antialias_pixels", "silhouette_pixels"]


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


def _pairs(frags: Fragments, verts_clip: torch.Tensor, faces: torch.Tensor):
    """Per direction (across, then down): ``(pa, pb, s)``, the flat indices of the adjacent pixel pairs
    (A, B) showing different triangles and where their boundary crosses (fraction from A to B; 0.5
    where none is found). Found from int32 face and float depth images made here (no index per pixel)."""
    B, H, W = frags.shape
    faces = faces.to(device=verts_clip.device, dtype=torch.long)
    n = B * H * W
    fid = torch.full((n,), -1, dtype=torch.int32, device=frags.pix.device).index_copy_(0, frags.pix,
                                                                                         frags.pix_face.int())
    depth = torch.full((n,), float("inf"), dtype=frags.pix_depth.dtype, device=frags.pix.device)
    depth.index_copy_(0, frags.pix, frags.pix_depth.detach())
    img = fid.view(B, H, W)
    for step, differs in ((1, img[:, :, :-1] != img[:, :, 1:]), (W, img[:, :-1, :] != img[:, 1:, :])):
        at = torch.nonzero(differs)
        del differs
        if at.numel() == 0:
            continue
        pa = (at[:, 0] * H + at[:, 1]) * W + at[:, 2]
        pb = pa + step
        s = _crossing(pa, pb, fid[pa].long(), fid[pb].long(), depth, verts_clip, faces, frags)
        yield pa, pb, torch.where(torch.isfinite(s), s, torch.full_like(s, 0.5))


def antialias(color: torch.Tensor, frags: Fragments, verts_clip: torch.Tensor, faces: torch.Tensor) -> torch.Tensor:
    """Blend colours across triangle boundaries according to where the edges cross.

    Args:
        color: (B, H, W, C) shaded image (background included) from the same rasterization.
        frags: :class:`Fragments` of ``rasterize(verts_clip, faces, ...)``, of the frame or of a
            window of it (then ``color`` is the window's and pairs reaching outside it are not seen).
        verts_clip: (B, V, 4) clip-space vertices that were rasterized.
        faces: (F, 3).

    Returns:
        (B, H, W, C) antialiased image.
    """
    B, H, W = frags.shape
    check_shape(color, [B, H, W, "C"], name="color")
    check_shape(verts_clip, [B, "V", 4], name="verts_clip")
    C = color.shape[-1]
    flat = color.reshape(-1, C)
    out = flat.clone()
    for pa, pb, s in _pairs(frags, verts_clip, faces):
        s = s.to(color.dtype)[:, None]
        ca, cb = flat[pa], flat[pb]
        out.index_add_(0, pb, (s - 0.5).clamp(min=0) * (ca - cb))
        out.index_add_(0, pa, (0.5 - s).clamp(min=0) * (cb - ca))
    return out.view(B, H, W, C)


@torch.no_grad()
def antialias_pixels(color_at, frags: Fragments, verts_clip: torch.Tensor, faces: torch.Tensor,
                     keep: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """:func:`antialias` at some pixels only, the colours asked for where they are needed.

    The same values as ``antialias(color, ...)`` at those pixels (the same additions in the same
    order) without a whole image of colours: a frame composited in 8 bits gets its silhouette
    antialiased from the few pixels along it.

    Args:
        color_at: ``color_at(idx (N,) int64) -> (N, C)`` the colours of pixels by flat index into B·H·W.
        frags, verts_clip, faces: as :func:`antialias`.
        keep: (B, H, W) bool the pixels wanted (e.g. :func:`silhouette_pixels`).

    Returns:
        ``(idx (M,) int64, colours (M, C))`` of the wanted pixels that a boundary changes.
    """
    B, H, W = frags.shape
    check_shape(keep, [B, H, W], name="keep")
    keep = keep.reshape(-1)
    found = []
    for pa, pb, s in _pairs(frags, verts_clip, faces):
        near = keep[pa] | keep[pb]
        found.append((pa[near], pb[near], s[near]))
    ends = [i[keep[i]] for pa, pb, _ in found for i in (pa, pb)]
    idx = torch.unique(torch.cat(ends)) if ends else torch.zeros(0, dtype=torch.long, device=keep.device)
    out = color_at(idx).clone()
    for pa, pb, s in found:
        ca, cb = color_at(pa), color_at(pb)
        s = s.to(ca.dtype)[:, None]
        for to, d in ((pb, (s - 0.5).clamp(min=0) * (ca - cb)), (pa, (0.5 - s).clamp(min=0) * (cb - ca))):
            at = torch.searchsorted(idx, to).clamp_max(max(idx.numel() - 1, 0))  # where ``to`` is in ``idx``
            wanted = idx[at] == to
            out.index_add_(0, at[wanted], d[wanted])
    return idx, out


def _crossing(pa, pb, fa, fb, depth, verts_clip, faces, frags: Fragments):
    """Boundary position (fraction from A to B) for pixel pairs; NaN where none is found."""
    V = verts_clip.shape[1]
    H, W = frags.region.frame  # pixel centres in the frame's NDC (a window's pixels as the frame's)
    bidx, ya, xa = frags.frame_pixels(pa)
    _, yb, xb = frags.frame_pixels(pb)

    def ndc(x, y):
        return (2 * x + 1).to(verts_clip.dtype) / W - 1, 1 - (2 * y + 1).to(verts_clip.dtype) / H

    ua, va = ndc(xa, ya)
    ub, vb = ndc(xb, yb)
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
    m = mask.bool()
    out = torch.zeros_like(m)
    rows, cols = m[1:] != m[:-1], m[:, 1:] != m[:, :-1]  # boolean images only (a frame at the limit: 12 MB each)
    out[1:] |= rows
    out[:-1] |= rows
    out[:, 1:] |= cols
    out[:, :-1] |= cols
    return out
