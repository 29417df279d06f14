"""Slow loop reference rasterizer for tests (pure Python scalars, small images only).

It implements the contract of :func:`relightnet.raster.rasterize` written out plainly:
clip each triangle against the near/far planes and the guard band (Sutherland–Hodgman,
intersections computed from the inside endpoint), snap vertices to 1/256 pixel, test
every pixel centre with exact integer edge functions and the top-left rule, keep the
nearest fragment, and compute perspective-correct barycentrics from the unclipped
clip-space vertices.
"""

from __future__ import annotations

import math

import torch

GUARD = 2.0
SUB = 256


def _dist(p):
    x, y, z, w = p
    gw = w * GUARD
    return [z + w, w - z, gw - x, gw + x, gw - y, gw + y, w - x, w + x, w - y, w + y]


def _clip(tri):
    """Clip a triangle (3 points (x, y, z, w)) against planes 0-5; return fan triangles."""
    d = [_dist(p) for p in tri]
    if all(all(v >= 0 for v in di[:6]) for di in d):
        return [tri]
    for k in range(10):
        if all(di[k] < 0 for di in d):
            return []
    poly = list(tri)
    for k in range(6):
        out = []
        for i, cur in enumerate(poly):
            nxt = poly[(i + 1) % len(poly)]
            dc, dn = _dist(cur)[k], _dist(nxt)[k]
            if dc >= 0:
                out.append(cur)
            if (dc >= 0) != (dn >= 0):
                a, b, da, db = (cur, nxt, dc, dn) if dc >= 0 else (nxt, cur, dn, dc)
                t = da / (da - db)
                out.append(tuple(a[j] + t * (b[j] - a[j]) for j in range(4)))
        poly = out
        if len(poly) < 3:
            return []
    return [(poly[0], poly[j], poly[j + 1]) for j in range(1, len(poly) - 1)]


def _snap(p, H, W):
    x, y, _, w = p
    return int(round((x / w + 1.0) * (W * SUB / 2))), int(round((1.0 - y / w) * (H * SUB / 2)))


def _covered(S, px, py):
    """Top-left rule coverage of pixel centre (px, py) (×256 units) by snapped triangle S."""
    (x0, y0), (x1, y1), (x2, y2) = S
    area2 = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    sgn = 1 if area2 > 0 else -1
    for (ax, ay), (bx, by) in (((x1, y1), (x2, y2)), ((x2, y2), (x0, y0)), ((x0, y0), (x1, y1))):
        e = sgn * ((bx - ax) * (py - ay) - (by - ay) * (px - ax))
        A, B = sgn * (ay - by), sgn * (bx - ax)  # inward normal of the edge
        top_left = A > 0 or (A == 0 and B > 0)
        if e < 0 or (e == 0 and not top_left):
            return False
    return True


def _bary_depth(tri, u, v):
    """Perspective-correct barycentrics and NDC depth at NDC (u, v) of a clip triangle."""
    cols = [(p[0], p[1], p[3]) for p in tri]
    rows = []
    for i in range(3):
        a, b = cols[(i + 1) % 3], cols[(i + 2) % 3]
        rows.append((a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]))
    bt = [r[0] * u + r[1] * v + r[2] for r in rows]
    s = sum(bt)
    bary = [b / s for b in bt]
    z = sum(bary[i] * tri[i][2] for i in range(3))
    w = sum(bary[i] * tri[i][3] for i in range(3))
    return bary, z / w


def reference_rasterize(verts_clip: torch.Tensor, faces: torch.Tensor, size, cull_backfaces=False):
    """Returns (face_id (B, H, W) int64, bary (B, H, W, 3) float64, depth (B, H, W) float64)."""
    H, W = size
    B = verts_clip.shape[0]
    vc = verts_clip.detach().double().tolist()
    fl = faces.tolist()
    face_id = torch.full((B, H, W), -1, dtype=torch.long)
    bary = torch.zeros(B, H, W, 3, dtype=torch.float64)
    depth = torch.full((B, H, W), math.inf, dtype=torch.float64)
    for b in range(B):
        for f, (i0, i1, i2) in enumerate(fl):
            tri = (tuple(vc[b][i0]), tuple(vc[b][i1]), tuple(vc[b][i2]))
            for piece in _clip(tri):
                S = [_snap(p, H, W) for p in piece]
                (x0, y0), (x1, y1), (x2, y2) = S
                area2 = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
                if area2 == 0 or (cull_backfaces and area2 > 0):
                    continue
                for i in range(H):
                    for j in range(W):
                        if not _covered(S, SUB * j + SUB // 2, SUB * i + SUB // 2):
                            continue
                        u = (2 * j + 1) / W - 1
                        v = 1 - (2 * i + 1) / H
                        bc, z = _bary_depth(tri, u, v)
                        if z < depth[b, i, j]:
                            depth[b, i, j] = z
                            face_id[b, i, j] = f
                            bary[b, i, j] = torch.tensor(bc, dtype=torch.float64)
    return face_id, bary, depth
