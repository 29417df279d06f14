"""Span stage of the rasterizer (internal): exact coverage, enumeration, z-buffer.

Snapped triangles (vertices in 1/256 pixel, integers held in float64) are turned into
(triangle, pixel row) pairs, the covered columns of each pair into one interval, and
the covered pixels into int64 z-buffer keys. The elementwise work lives in pure
``_*_kernel`` functions (no data-dependent shapes) so that
:func:`relightnet.raster.rasterize` can run them eagerly or through ``torch.compile``;
the data-dependent steps (``repeat_interleave``, ``scatter_reduce_``) stay eager.
"""

from __future__ import annotations

import logging

import torch

logger = logging.getLogger(__name__)

SUB = 256.0  # subpixel steps per pixel
KEY_MAX = torch.iinfo(torch.int64).max
_TINY = 2.0**-40  # |D| given to horizontal edges (see _edge_kernel)
_CHUNK = 1 << 20  # (triangle, row) pairs or pixels per chunk

# Edge slots by the pattern l0 + 2 l1 + 4 l2 (l_i: edge i bounds columns from below):
# two lower-bound edges then two upper-bound edges, one repeated when a side has one.
_SLOTS = [[0, 0, 1, 2], [0, 0, 1, 2], [1, 1, 0, 2], [0, 1, 2, 2],
          [2, 2, 0, 1], [0, 2, 1, 1], [1, 2, 0, 0], [0, 1, 2, 2]]


def _edge_kernel(X, Y, zplane, det, lo_y, hi_y, slots, cull_backfaces: bool, H: int, W: int):
    """Exact edge data of snapped triangles X, Y (3, n) in slot order.

    A pixel (column x, row y) is covered by edge s iff ``G_s + Gy_s·y >= D_s·x``:
    E(x, y) = A(256x + 128) + B(256y + 128) + C + bias with bias −1 off top/left edges
    (so E > 0 is required there), D = −256A, G = 128(A + B) + C + bias, Gy = 256B.
    Lower-bound edges (A >= 0, slots 0–1) give x >= ceil((G + Gy·y) / D), upper ones
    (slots 2–3) x <= floor(...). Horizontal edges get D = −2^−40: no bound when
    G + Gy·y >= 0, an empty span otherwise. All values are integers below 2^51, so the
    quotient's ceil/floor is exact.

    Returns Ds, Gs, Gys (4, n), depth plane in pixel indices zc (+2), zx, zy (n,), and the
    number of pixel rows per triangle (0 for degenerate or culled ones).
    """
    Xe = torch.cat([X, X[:2]])
    Ye = torch.cat([Y, Y[:2]])
    X1, X2, Y1, Y2 = Xe[1:4], Xe[2:5], Ye[1:4], Ye[2:5]
    A = Y1 - Y2
    Bc = X2 - X1
    C = X1 * Y2 - X2 * Y1  # exact: |coordinates| < 2^23
    area2 = C[0] + C[1] + C[2]
    # With y down, a counter-clockwise NDC triangle has area2 < 0.
    keep = ((area2 < 0) if cull_backfaces else (area2 != 0)) & (det != 0)
    s = torch.sign(area2)
    A, Bc, C = A * s, Bc * s, C * s
    top_left = (A > 0) | ((A == 0) & (Bc > 0))
    G = (A + Bc) * (SUB / 2) + C + (top_left.to(C.dtype) - 1.0)
    D = torch.where(A == 0, torch.full_like(A, -_TINY), A * -SUB)
    lower = (A >= 0).long()
    slot = torch.index_select(slots, 0, lower[0] + 2 * lower[1] + 4 * lower[2]).T  # (4, n)
    Ds = torch.gather(D, 0, slot)
    Gs = torch.gather(G, 0, slot)
    Gys = torch.gather(Bc * SUB, 0, slot)
    zx = zplane[0] * (2.0 / W)
    zy = zplane[1] * (-2.0 / H)
    zc = zplane[0] * (1.0 / W - 1.0) + zplane[1] * (1.0 - 1.0 / H) + zplane[2] + 2.0
    nrows = torch.where(keep, hi_y - lo_y + 1.0, torch.zeros_like(lo_y)).long()
    return Ds, Gs, Gys, zc, zx, zy, nrows


def _pair_kernel(t, off, Ds, Gs, Gys, zc, zx, zy, base, top: int, left: int, w: int):
    """Covered column interval of each (triangle t, row) pair; row = pair index + off[t].

    Rows and columns are the frame's; the columns are cut to the window's ``left .. left + w − 1``,
    and pixel indices are the window's (of ``w`` columns, its row 0 the frame's row ``top``).
    Returns count (int64), flat pixel index of the first covered pixel (int64), depth (+2)
    there and the depth step per column.
    """
    y = torch.arange(t.shape[0], device=t.device, dtype=torch.float64) + off.index_select(0, t)
    q = [torch.addcmul(Gs[i].index_select(0, t), Gys[i].index_select(0, t), y) / Ds[i].index_select(0, t)
         for i in range(4)]
    x0 = torch.clamp(torch.maximum(torch.ceil(q[0]), torch.ceil(q[1])), min=float(left))
    x1 = torch.clamp(torch.minimum(torch.floor(q[2]), torch.floor(q[3])), max=left + w - 1.0)
    cnt = torch.clamp(x1 - x0 + 1.0, min=0.0).long()
    zxp = zx.index_select(0, t)
    pixoff = torch.addcmul(base.index_select(0, t) + (x0 - left), y - top, torch.full_like(y, w)).long()
    zoff = torch.addcmul(torch.addcmul(zc.index_select(0, t), zy.index_select(0, t), y), zxp, x0)
    return cnt, pixoff, zoff, zxp


def _emit_kernel(pair, start, pixoff, zoff, zxp, tid, fbits: int):
    """Pixels of spans: flat index and z-buffer key (depth + 2 bits | triangle index)."""
    i = torch.arange(pair.shape[0], device=pair.device) - start.index_select(0, pair)
    pix = pixoff.index_select(0, pair) + i
    # depth + 2 > 0, so its float64 bits order like its value (clamped: far-off planes)
    z = torch.clamp(torch.addcmul(zoff.index_select(0, pair), zxp.index_select(0, pair), i.to(zoff.dtype)),
                    min=0.25)
    key = torch.bitwise_or(torch.bitwise_and(z.view(torch.int64), -(1 << fbits)), tid.index_select(0, pair))
    return pix, key


def chunks(counts: torch.Tensor, limit: int = _CHUNK) -> list[tuple[int, int]]:
    """Split range(len(counts)) into consecutive pieces whose counts sum to about ``limit``."""
    n = counts.shape[0]
    if n == 0:
        return []
    cum = torch.cumsum(counts, 0)
    total = int(cum[-1])
    if total <= limit:
        return [(0, n)]
    ends = torch.searchsorted(cum, torch.arange(limit, total + limit, limit, device=cum.device),
                              right=True).tolist()
    out, a = [], 0
    for b in ends:
        b = min(max(b, a + 1), n)
        if b > a:
            out.append((a, b))
        a = b
    if a < n:
        out.append((a, n))
    return out


class ZBuffer:
    """Nearest-key z-buffer over B·H·W pixels.

    Candidate (pixel, key) pairs are kept while they are fewer than the pixels, so the
    winners are found without scanning the whole buffer.
    """

    def __init__(self, n_pix: int, n_tri: int, device) -> None:
        self.buf = torch.full((n_pix,), KEY_MAX, dtype=torch.int64, device=device)
        self.fbits = max(1, int(n_tri - 1).bit_length())
        self.kept: list[tuple[torch.Tensor, torch.Tensor]] | None = []
        self.count = 0

    def add(self, pix: torch.Tensor, key: torch.Tensor) -> None:
        self.buf.scatter_reduce_(0, pix, key, reduce="amin")
        self.count += pix.shape[0]
        if self.kept is not None:
            self.kept = None if self.count > self.buf.shape[0] else self.kept + [(pix, key)]

    def winners(self) -> tuple[torch.Tensor, torch.Tensor]:
        """(pix, triangle index) of the nearest candidate of every covered pixel."""
        mask = (1 << self.fbits) - 1
        if self.kept is None:
            pix = torch.nonzero(self.buf != KEY_MAX).squeeze(1)
            return pix, self.buf.index_select(0, pix) & mask
        pix_l, key_l = [], []
        for pix, key in self.kept:
            win = torch.nonzero(self.buf.index_select(0, pix) == key).squeeze(1)
            pix_l.append(pix.index_select(0, win))
            key_l.append(key.index_select(0, win))
        if not pix_l:
            empty = torch.zeros(0, dtype=torch.long, device=self.buf.device)
            return empty, empty
        return torch.cat(pix_l), torch.cat(key_l) & mask


def rasterize_spans(zb: ZBuffer, X, Y, lo_y, hi_y, zplane, det, base, size: tuple[int, int],
                    cull_backfaces: bool, kernels, window: tuple[int, int, int]) -> None:
    """Z-test every covered pixel of the snapped triangles X, Y (3, n) into ``zb``.

    lo_y, hi_y: (n,) first/last pixel row (the frame's, within the window); zplane (3, n) NDC
    depth = zplane · (u, v, 1); det (n,) 0 for degenerate triangles; base (n,) flat offset of each
    triangle's image in ``zb``; size (H, W) the frame's; window (top, left, width): the window's first
    row and column and its width (``zb`` holds the window's pixels). ``kernels`` maps kernel names to
    callables (eager or compiled).
    """
    H, W = size
    slots = torch.tensor(_SLOTS, device=X.device)
    Ds, Gs, Gys, zc, zx, zy, nrows = kernels["edge"](X, Y, zplane, det, lo_y, hi_y, slots,
                                                      cull_backfaces, H, W)
    for a, b in chunks(nrows):
        nr = nrows[a:b]
        P = int(nr.sum())
        if P == 0:
            continue
        t = torch.repeat_interleave(nr, output_size=P)  # triangle of each (triangle, row) pair
        off = lo_y[a:b] - (torch.cumsum(nr, 0) - nr)
        cnt, pixoff, zoff, zxp = kernels["pair"](t, off, Ds[:, a:b], Gs[:, a:b], Gys[:, a:b], zc[a:b],
                                                 zx[a:b], zy[a:b], base[a:b], *window)
        tid = t + a
        for c, d in chunks(cnt):
            cn = cnt[c:d]
            N = int(cn.sum())
            if N == 0:
                continue
            pair = torch.repeat_interleave(cn, output_size=N)
            pix, key = kernels["emit"](pair, torch.cumsum(cn, 0) - cn, pixoff[c:d], zoff[c:d], zxp[c:d],
                                       tid[c:d], zb.fbits)
            zb.add(pix, key)
