"""Pure-torch triangle rasterizer: clip-space triangles → :class:`Fragments`.

How it works (all steps vectorised, device-agnostic, no extension):

1. **Clip.** Triangles crossing the near/far plane or the guard band (|x|, |y| > 2w)
   are clipped in homogeneous space (:mod:`.clip`), so nothing behind the camera
   wraps around; triangles entirely outside one plane are dropped.
2. **Snap.** Vertices go to pixel coordinates snapped to 1/256 pixel and held as
   integers in float64; edge functions ``E = A·x + B·y + C`` are then exact, and an
   edge shared by two triangles gives exactly opposite values.
3. **Fill rule.** A pixel centre is covered when every edge function is positive, or
   zero on a *top* or *left* edge (the Direct3D/OpenGL top-left rule): two triangles
   sharing an edge cover each pixel once and a closed mesh has no cracks. Both
   orientations are rasterized unless ``cull_backfaces`` (front faces are
   counter-clockwise in NDC, the OpenGL default).
4. **Spans** (:mod:`.spans`). Every (triangle, pixel row) pair is enumerated; its
   covered columns form one interval, found exactly from the edge functions (ceil/floor
   of an exact quotient). Covered pixels are enumerated without testing uncovered ones.
5. **Z-buffer.** Each covered (pixel, triangle) pair becomes one int64 key: the float64
   bit pattern of ``depth + 2`` (positive, so the bits sort like the value) in the high
   bits and the triangle's index in the low bits; ``scatter_reduce_(amin)`` keeps the
   nearest triangle per pixel (exact ties go to the lower index).
6. **Barycentrics.** On covered pixels only, perspective-correct barycentrics and NDC
   depth at the pixel centre, from the unsnapped vertices: screen-space barycentrics
   divided by w (homogeneous 2D rasterization for clipped triangles).

Rasterization is not differentiable (outputs are detached); interpolation is.
``compile=True`` runs the elementwise stages through ``torch.compile`` (several times
faster on CPU once compiled; the first call compiles for tens of seconds and needs a C++
compiler); if compilation fails it logs a warning and falls back to eager code.
"""

from __future__ import annotations

import logging

import torch

from ..checks import InputError, check_finite, check_shape
from .clip import GUARD_BAND, clip_triangles, outcodes
from .fragments import Fragments
from .spans import SUB, ZBuffer, _edge_kernel, _emit_kernel, _pair_kernel, rasterize_spans
from .window import Window

__all__ = ["rasterize", "screen_box"]

logger = logging.getLogger(__name__)

#: Largest image side: keeps snapped coordinates (guard band included) below 2^23 subpixel
#: steps, so every edge-function value is an integer below 2^53, exact in float64.
_MAX_SIZE = 16384
#: Covered pixels whose barycentrics are computed at once (about 100 bytes of float64 temporaries each).
_BARY_CHUNK = 1 << 18


def _snap_ndc(u, v, H: int, W: int):
    """NDC x, y (float64) → pixel coordinates ×256 snapped to integers (x right, y down)."""
    return torch.round((u + 1.0) * (W * SUB / 2)), torch.round((1.0 - v) * (H * SUB / 2))


def _box_kernel(sx, sy, top: int, left: int, bottom: int, right: int):
    """Pixel rows/columns whose centres lie in the boxes of triangles (3, n), within the window.

    sx, sy: vertex positions in pixel units relative to pixel centres (snapped / 256 − 0.5).
    top, left, bottom, right: the window's first/last row and column (the frame's pixels).
    Returns (nonempty (n,) bool, lo_x, hi_x, lo_y, hi_y) clamped to the window.
    """
    lo_x = torch.ceil(torch.minimum(torch.minimum(sx[0], sx[1]), sx[2])).clamp_(min=left)
    hi_x = torch.floor(torch.maximum(torch.maximum(sx[0], sx[1]), sx[2])).clamp_(max=right)
    lo_y = torch.ceil(torch.minimum(torch.minimum(sy[0], sy[1]), sy[2])).clamp_(min=top)
    hi_y = torch.floor(torch.maximum(torch.maximum(sy[0], sy[1]), sy[2])).clamp_(max=bottom)
    return (lo_x <= hi_x) & (lo_y <= hi_y), lo_x, hi_x, lo_y, hi_y


def _plane_kernel(u, v, zn, iw):
    """Triangles with NDC vertices u, v, depth zn and 1/w (3, n each), all in front.

    Returns rows (3 comps, 3 vertices, n), zplane (3, n), det (n,): the perspective-correct
    weight of vertex i at NDC (u, v) is proportional to ``rows[:, i] · (u, v, 1)`` (the
    screen-space barycentric λ_i, affine in (u, v), divided by w_i); NDC depth is
    ``zplane · (u, v, 1)``; det = 0 marks degenerate triangles.
    """
    du1, du2 = u[1] - u[0], u[2] - u[0]
    dv1, dv2 = v[1] - v[0], v[2] - v[0]
    det = du1 * dv2 - du2 * dv1
    inv = 1.0 / torch.where(det == 0, torch.ones_like(det), det)
    # λ_1 = a1 u + b1 v + c1, λ_2 = a2 u + b2 v + c2, λ_0 = 1 − λ_1 − λ_2
    a1, b1 = dv2 * inv, du2 * -inv
    a2, b2 = dv1 * -inv, du1 * inv
    c1 = -torch.addcmul(a1 * u[0], b1, v[0])
    c2 = -torch.addcmul(a2 * u[0], b2, v[0])
    dz1, dz2 = zn[1] - zn[0], zn[2] - zn[0]
    zplane = torch.stack([torch.addcmul(a1 * dz1, a2, dz2), torch.addcmul(b1 * dz1, b2, dz2),
                          torch.addcmul(torch.addcmul(zn[0], c1, dz1), c2, dz2)])
    rows = torch.stack([
        torch.stack([-(a1 + a2) * iw[0], a1 * iw[1], a2 * iw[2]]),
        torch.stack([-(b1 + b2) * iw[0], b1 * iw[1], b2 * iw[2]]),
        torch.stack([(1.0 - (c1 + c2)) * iw[0], c1 * iw[1], c2 * iw[2]]),
    ])
    return rows, zplane, det


def _homogeneous(cx, cy, cz, cw):
    """Like :func:`_plane_kernel` from clip coordinates (3, n each), any w (clipped triangles).

    ``rows[:, i] = c_{i+1} × c_{i+2}`` with ``c_i = (x_i, y_i, w_i)`` (2D homogeneous
    rasterization).
    """
    x1, y1, w1 = cx.roll(-1, 0), cy.roll(-1, 0), cw.roll(-1, 0)
    x2, y2, w2 = cx.roll(-2, 0), cy.roll(-2, 0), cw.roll(-2, 0)
    rows = torch.stack([y1 * w2 - w1 * y2, w1 * x2 - x1 * w2, x1 * y2 - y1 * x2])
    det = cx[0] * rows[0, 0] + cy[0] * rows[1, 0] + cw[0] * rows[2, 0]
    inv = 1.0 / torch.where(det == 0, torch.ones_like(det), det)
    zplane = (cz[None] * rows).sum(1) * inv
    return rows, zplane, det


def _bary_kernel(pix, t, rows, zplane, gid, grid: tuple[int, int, int, int, int, int, int, int]):
    """Barycentrics (3, N) float64, NDC depth (N,) and face index (N,) of covered pixels.

    pix: flat indices into the B·h·w pixels of the window at (top, left) of the (H, W) frame; the
    pixel centres' NDC are the frame's (for the whole frame the same operations as without a window).
    grid: ``(B, F, h, w, top, left, H, W)``, the batch, the faces per mesh, the window and the frame.
    """
    B, F, h, w, top, left, H, W = grid
    pf = pix.to(torch.float64)
    if B > 1:
        pf = pf - torch.floor(pf / (h * w)) * (h * w)
    py = torch.floor(pf / w)  # exact: integers below 2^53
    u = (pf - py * w + left) * (2.0 / W) + (1.0 / W - 1.0)
    v = (py + top) * (-2.0 / H) + (1.0 - 1.0 / H)
    r = rows.reshape(9, -1)
    bt = [torch.addcmul(torch.addcmul(r[6 + i].index_select(0, t), r[i].index_select(0, t), u),
                        r[3 + i].index_select(0, t), v) for i in range(3)]
    inv = 1.0 / (bt[0] + bt[1] + bt[2])
    bary = torch.stack([bt[0] * inv, bt[1] * inv, bt[2] * inv])
    depth = torch.addcmul(torch.addcmul(zplane[2].index_select(0, t), zplane[0].index_select(0, t), u),
                          zplane[1].index_select(0, t), v)
    face = gid.index_select(0, t)
    if B > 1:
        face = face % F
    return bary, depth, face


_EAGER = {"box": _box_kernel, "plane": _plane_kernel, "edge": _edge_kernel, "pair": _pair_kernel,
          "emit": _emit_kernel, "bary": _bary_kernel}
_COMPILED: dict[str, object] = {}


def _compiled_kernels() -> dict:
    """Kernels through ``torch.compile`` (dynamic shapes), each falling back to eager on error."""
    if not _COMPILED:
        for name, fn in _EAGER.items():
            _COMPILED[name] = _Fallback(name, fn)
    return _COMPILED


class _Fallback:
    """Calls the compiled kernel; on any compilation/runtime failure switches to eager for good."""

    def __init__(self, name, fn) -> None:
        self.name, self.eager = name, fn
        self.fn = torch.compile(fn, dynamic=True)

    def __call__(self, *args):
        if self.fn is not self.eager:
            try:
                return self.fn(*args)
            except Exception as exc:  # no C++ compiler, unsupported backend, ...
                logger.warning("torch.compile of raster kernel %r failed (%s: %s); using eager code",
                               self.name, type(exc).__name__, exc)
                self.fn = self.eager
        return self.eager(*args)


def rasterize(verts_clip: torch.Tensor, faces: torch.Tensor, size, cull_backfaces: bool = False,
              check: bool = True, compile: bool = False, window: Window | None = None) -> Fragments:
    """Rasterize triangles given in clip space into (B, H, W) fragments.

    Args:
        verts_clip: (B, V, 4) clip-space vertices (``Camera.transform``), float32/float64.
        faces: (F, 3) int64 vertex indices shared by the batch.
        size: (H, W) the frame's size (pixel convention of :mod:`relightnet.raster.camera`), at most
            16384 each.
        cull_backfaces: drop triangles that are clockwise in NDC (seen from behind).
        check: validate the inputs (shapes, finiteness, index range).
        compile: run the elementwise stages through ``torch.compile`` (module docstring).
        window: a :class:`Window` of the (H, W) frame: only its pixels are rasterized, every buffer
            is its size, and the fragments are bit for bit the whole frame's at those pixels (the
            same snapped triangles, depths and pixel-centre NDC; e.g. :func:`screen_box`'s). None:
            the whole frame.

    Returns:
        :class:`Fragments` for the nearest triangle of every pixel: ``face_id`` (B, h, w)
        (−1 = background), perspective-correct ``bary`` (B, h, w, 3) and NDC ``depth``
        (B, h, w) (+inf = background), in ``verts_clip``'s dtype; (h, w) is the window's size
        ((H, W) without one) and ``Fragments.window`` the window.

    Example:
        Two triangles in clip space (w = 1) that cover the whole frame:

        >>> import torch
        >>> from relightnet.raster import rasterize
        >>> verts = torch.tensor([[[-1.0, -1.0, 0.0, 1.0], [1.0, -1.0, 0.0, 1.0],
        ...                        [1.0, 1.0, 0.0, 1.0], [-1.0, 1.0, 0.0, 1.0]]])
        >>> faces = torch.tensor([[0, 1, 2], [0, 2, 3]])
        >>> frags = rasterize(verts, faces, (4, 6))
        >>> frags.face_id.shape, bool((frags.face_id >= 0).all())
        (torch.Size([1, 4, 6]), True)
        >>> torch.allclose(frags.bary.sum(-1), torch.ones(1, 4, 6))
        True
    """
    H, W = int(size[0]), int(size[1])
    if check:
        _check(verts_clip, faces, H, W)
    win = _window(window, H, W)
    k = _compiled_kernels() if compile else _EAGER
    dev = verts_clip.device
    out_dtype = verts_clip.dtype
    B = verts_clip.shape[0]
    F = faces.shape[0]
    shape = (B, win.height, win.width)
    if B * F == 0:
        e = torch.zeros(0, dtype=torch.long, device=dev)
        return Fragments(e, e, torch.zeros(0, 3, dtype=out_dtype, device=dev),
                         torch.zeros(0, dtype=out_dtype, device=dev), shape, window)
    X, Y, _, _, lo_y, hi_y, gid, rows, zplane, det = _triangles(verts_clip, faces, H, W, win, k)
    n = gid.shape[0]
    hw = win.height * win.width
    zb = ZBuffer(B * hw, n, dev)
    base = torch.div(gid, F, rounding_mode="floor").to(torch.float64) * hw
    rasterize_spans(zb, X, Y, lo_y, hi_y, zplane, det, base, (H, W), cull_backfaces, k,
                    (win.top, win.left, win.width))
    pix, t = zb.winners()
    del zb  # the z-buffer and its candidates before the covered pixels' barycentrics
    # pix_bary is (N, 3) with contiguous columns: consumers read it per vertex
    bary = torch.empty(3, pix.shape[0], dtype=out_dtype, device=dev)
    depth = torch.empty(pix.shape[0], dtype=out_dtype, device=dev)
    face = torch.empty_like(pix)
    grid = (B, F, win.height, win.width, win.top, win.left, H, W)
    for a in range(0, pix.shape[0], _BARY_CHUNK):  # float64 temporaries of a chunk at a time
        s = slice(a, a + _BARY_CHUNK)
        bary[:, s], depth[s], face[s] = k["bary"](pix[s], t[s], rows, zplane, gid, grid)
    return Fragments(pix, face, bary.T, depth, shape, window)


def screen_box(verts_clip: torch.Tensor, faces: torch.Tensor, size, pad: int = 2,
               check: bool = True) -> Window | None:
    """The smallest :class:`Window` holding every pixel that :func:`rasterize` can cover, padded.

    Found from the rasterizer's own triangles (snapped, and clipped where they cross the near or
    far plane or the guard band, so a triangle behind the camera adds only what it can show): the
    union of the boxes of pixel centres each one spans in the frame (over the batch), grown by
    ``pad`` pixels on each side and cut to the frame. ``rasterize(..., window=screen_box(...))``
    then covers the same pixels as the whole frame, and with ``pad >= 1`` every pixel next to a
    covered one is in the window too (what :func:`relightnet.raster.antialias` looks at).

    Args:
        verts_clip: (B, V, 4) clip-space vertices.
        faces: (F, 3) int64.
        size: (H, W) the frame's size.
        pad: pixels added on each side, >= 0.
        check: validate the inputs.

    Returns:
        The window, or None when no triangle can cover a pixel centre of the frame.
    """
    H, W = int(size[0]), int(size[1])
    if check:
        _check(verts_clip, faces, H, W)
    if isinstance(pad, bool) or int(pad) < 0:
        raise InputError(f"pad: expected an integer >= 0, got {pad!r}")
    if verts_clip.shape[0] * faces.shape[0] == 0:
        return None
    _, _, lo_x, hi_x, lo_y, hi_y, _, _, _, _ = _triangles(verts_clip, faces, H, W, Window.full((H, W)), _EAGER)
    if lo_x.numel() == 0:
        return None
    p = int(pad)
    top, left = max(int(lo_y.min()) - p, 0), max(int(lo_x.min()) - p, 0)
    bottom, right = min(int(hi_y.max()) + p, H - 1), min(int(hi_x.max()) + p, W - 1)
    return Window(top, left, bottom - top + 1, right - left + 1, (H, W))


def _window(window, H: int, W: int) -> Window:
    if window is None:
        return Window.full((H, W))
    if not isinstance(window, Window) or window.frame != (H, W):
        raise InputError(f"window: expected a Window of the ({H}, {W}) frame, got {window!r}")
    return window


def _triangles(verts_clip, faces, H: int, W: int, win: Window, k):
    """The triangles (and clipped pieces) whose box holds a pixel centre of the window.

    Returns X, Y (3, n) snapped vertices, lo_x, hi_x, lo_y, hi_y (n,) their boxes in the window,
    gid (n,) index into the B·F faces, rows (3, 3, n), zplane (3, n), det (n,) (:func:`_plane_kernel`).
    """
    dev = verts_clip.device
    B, V = verts_clip.shape[:2]
    BF = B * faces.shape[0]
    bounds = (win.top, win.left, win.top + win.height - 1, win.left + win.width - 1)
    cx, cy, cz, cw = verts_clip.detach().to(torch.float64).reshape(B * V, 4).T.contiguous()
    # (3·B·F) vertex indices into the flattened (B·V) vertices, vertex-major
    fv = (faces.to(device=dev, dtype=torch.long).T[:, None, :]
          + (torch.arange(B, device=dev) * V)[None, :, None]).reshape(3 * BF)

    # Per vertex: inside the clip volume (near/far, guard band)? NDC and snapped coordinates.
    gw = cw * GUARD_BAND
    inside = (cx.abs() <= gw) & (cy.abs() <= gw) & (cz.abs() <= cw)
    all_inside = bool(inside.all())
    u, v = cx / cw, cy / cw
    Xv, Yv = _snap_ndc(u, v, H, W)

    # Per face: every vertex inside, and a pixel centre in the box → rasterized directly.
    half = SUB / 2
    ok, lo_x, hi_x, lo_y, hi_y = k["box"](((Xv - half) / SUB).index_select(0, fv).view(3, BF),
                                          ((Yv - half) / SUB).index_select(0, fv).view(3, BF), *bounds)
    if not all_inside:
        ins = inside.index_select(0, fv).view(3, BF)
        allin = ins[0] & ins[1] & ins[2]
        ok = ok & allin
    gid = torch.nonzero(ok).squeeze(1)
    n = gid.shape[0]
    tv = (gid[None] + torch.arange(0, 3 * BF, BF, device=dev)[:, None]).view(-1)
    tv = fv.index_select(0, tv)  # (3·n) vertex of each selected corner
    X = Xv.index_select(0, tv).view(3, n)
    Y = Yv.index_select(0, tv).view(3, n)
    boxes = [b.index_select(0, gid) for b in (lo_x, hi_x, lo_y, hi_y)]
    rows, zplane, det = k["plane"](*(a.index_select(0, tv).view(3, n) for a in (u, v, cz / cw, 1.0 / cw)))
    out = (X, Y, *boxes, gid, rows, zplane, det)
    if not all_inside:
        need = torch.nonzero(~allin).squeeze(1)
        if need.numel():
            out = _add_clipped(need, fv, (cx, cy, cz, cw), BF, H, W, bounds, out)
    return out


def _check(verts_clip, faces, H, W) -> None:
    dims = check_shape(verts_clip, ["B", "V", 4], name="verts_clip")
    check_shape(faces, ["F", 3], name="faces")
    if faces.dtype not in (torch.int64, torch.int32):
        raise InputError(f"faces: expected an integer tensor, got {faces.dtype}")
    if faces.numel() and (int(faces.min()) < 0 or int(faces.max()) >= dims["V"]):
        raise InputError(f"faces: indices must lie in [0, {dims['V']})")
    if not (0 < H <= _MAX_SIZE and 0 < W <= _MAX_SIZE):
        raise InputError(f"size: expected 1 <= H, W <= {_MAX_SIZE}, got ({H}, {W})")
    if not verts_clip.dtype.is_floating_point:
        raise InputError(f"verts_clip: expected a floating tensor, got {verts_clip.dtype}")
    check_finite(verts_clip, "verts_clip")


def _add_clipped(need, fv, comps, BF, H, W, bounds, tris):
    """Clip faces ``need`` (some vertex outside the clip volume); append the pieces to ``tris``
    (the tuple :func:`_triangles` returns)."""
    sel3 = (need[None] + torch.arange(0, 3 * BF, BF, device=need.device)[:, None]).view(-1)
    tv = fv.index_select(0, sel3)
    t = torch.stack([c.index_select(0, tv).view(3, -1) for c in comps], dim=-1).transpose(0, 1)
    codes = outcodes(t)  # (m, 3)
    live = torch.nonzero((codes[:, 0] & codes[:, 1] & codes[:, 2]) == 0).squeeze(1)
    if live.numel() == 0:
        return tris
    t = t.index_select(0, live)
    pieces, loc = clip_triangles(t, torch.arange(live.shape[0], device=need.device))
    pieces = pieces.permute(2, 1, 0)  # (4, 3, m')
    Xp, Yp = _snap_ndc(pieces[0] / pieces[3], pieces[1] / pieces[3], H, W)
    ok, *boxes = _box_kernel((Xp - SUB / 2) / SUB, (Yp - SUB / 2) / SUB, *bounds)
    keep = torch.nonzero(ok).squeeze(1)
    loc = loc.index_select(0, keep)
    # barycentrics and depth refer to the original (unclipped) triangle
    prow, pz, pdet = _homogeneous(*t.index_select(0, loc).permute(2, 1, 0))
    X, Y, lo_x, hi_x, lo_y, hi_y, gid, rows, zplane, det = tris
    return (torch.cat([X, Xp[:, keep]], 1), torch.cat([Y, Yp[:, keep]], 1),
            *(torch.cat([a, b[keep]]) for a, b in zip((lo_x, hi_x, lo_y, hi_y), boxes, strict=True)),
            torch.cat([gid, need.index_select(0, live).index_select(0, loc)]),
            torch.cat([rows, prow], 2), torch.cat([zplane, pz], 1), torch.cat([det, pdet]))
