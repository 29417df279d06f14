"""Garment and hair geometry around a posed body: offset shells and hanging ring surfaces.

Two primitives build every garment the generator (and later the avatar) dresses a body in;
both are pure functions of one posed frame, so a clip calls them per frame and the pieces
move with the body:

- :func:`shell_surface`: a copy of some of the body's faces pushed out along a direction
  (the vertex normals, or a blend with a radial direction) by a per-vertex offset, with an
  optional gravity sag of the parts whose normals point down. Each shell vertex follows
  its source body vertex, so the shell is skinned with the body's own weights (linear
  blend skinning through the joints): tops, jackets, open coats (faces removed in a
  front strip), trousers from tight to wide, volume hair over the scalp. The source
  vertex indices come back so that the caller can reuse the body's UVs.
- :func:`ring_surface`: a surface of horizontal rings around a vertical axis through a
  joint, from ``y_top`` down to ``y_bottom``, whose radius at every ring and angle is at
  least the body's horizontal extent there plus a clearance (so the body cannot show
  through at the sampled heights), made to *hang* (the radius never shrinks going down,
  as cloth or hair falls under gravity) and optionally opened at the front below a
  height (a face opening). Skirts and dresses (not following the legs), hoods, hats and
  long hair falling over the shoulders. It carries its own (u, v) grid coordinates.

Two more cut a piece's open border along a smooth line instead of its face edges (the avatar's
hems, :mod:`relightnet.pipeline.outfit_parts`): :func:`hem_field`, 0 on the border and rising
with the distance from it, and :func:`iso_clip`, which keeps the part of a mesh on one side of
an iso-line of a field, cutting the triangles it crosses.

Shapes: V body vertices, F body faces, N points; a piece has Vg vertices and Fg faces.
World frame: y up (docs/design.md, "Frames").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from ..checks import InputError, check_shape
from .base import vertex_normals

__all__ = ["GarmentPiece", "RingShape", "shell_surface", "ring_surface", "radial_directions", "hem_field", "iso_clip"]


@dataclass(frozen=True, eq=False)
class GarmentPiece:
    """One garment or hair mesh of one frame.

    Attributes:
        verts: (Vg, 3) float32 positions. normals: (Vg, 3) float32 unit vertex normals.
        faces: (Fg, 3) int64 triangles into ``verts``, counter-clockwise seen from outside.
        source: (Vg,) int64 body vertex each shell vertex follows (shells), or None (rings).
        source_faces: (Fg,) int64 body face each shell face copies (shells), or None.
        uv: (Vg, 2) float32 grid coordinates in [0, 1]² (rings: u around, v = 1 at the top), or None.
    """

    verts: torch.Tensor
    normals: torch.Tensor
    faces: torch.Tensor
    source: torch.Tensor | None = None
    source_faces: torch.Tensor | None = None
    uv: torch.Tensor | None = None


def radial_directions(verts: torch.Tensor, a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """(N, 3) unit directions from the segment a → b (an axis such as hip → ankle) to the points (N, 3)."""
    check_shape(verts, ["N", 3], name="verts")
    d = (b - a).to(verts)
    t = ((verts - a.to(verts)) @ d / (d @ d).clamp_min(1e-12)).clamp(0.0, 1.0)
    r = verts - (a.to(verts) + t[:, None] * d)
    return r / r.norm(dim=1, keepdim=True).clamp_min(1e-9)


def shell_surface(verts: torch.Tensor, normals: torch.Tensor, faces: torch.Tensor, face_sel: torch.Tensor,
                  offset: torch.Tensor, direction: torch.Tensor | None = None, sag: torch.Tensor | float = 0.0
                  ) -> GarmentPiece:
    """An offset copy of the selected body faces.

    Vertex i moves to ``p_i + offset_i · d_i`` (``d`` = ``direction`` or the normals), then
    down by ``sag_i · max(−n_y, 0)`` (cloth under an arm or a belly hangs away from it).

    Args:
        verts: (V, 3) posed body positions. normals: (V, 3) unit body normals.
        faces: (F, 3) body faces. face_sel: (F,) bool, the faces the garment covers.
        offset: (V,) distance (metres) along ``direction``; only the selected faces' vertices are used.
        direction: (V, 3) unit push directions, default the normals.
        sag: float or (V,) gravity sag (metres).

    Returns:
        :class:`GarmentPiece` with ``source`` and ``source_faces`` set.
    """
    check_shape(verts, ["V", 3], name="verts")
    nv = verts.shape[0]
    check_shape(normals, [nv, 3], name="normals")
    check_shape(faces, ["F", 3], name="faces")
    check_shape(face_sel, [faces.shape[0]], name="face_sel")
    check_shape(offset, [nv], name="offset")
    fidx = torch.nonzero(face_sel.bool()).flatten()
    if fidx.numel() == 0:
        raise InputError("face_sel: selects no face")
    sub = faces[fidx]
    src, local = torch.unique(sub, return_inverse=True)
    p, n = verts[src].double(), normals[src].double()
    d = n if direction is None else direction[src].double()
    sag = torch.as_tensor(sag, dtype=torch.float64)
    sag_v = sag.expand(nv)[src] if sag.dim() else sag
    q = p + offset[src].double()[:, None] * d
    q[:, 1] -= sag_v * (-n[:, 1]).clamp_min(0.0)
    q = q.float()
    f = local.reshape(-1, 3)
    return GarmentPiece(q, vertex_normals(q, f), f, source=src, source_faces=fidx)


def _ring_radii(points: torch.Tensor, centre: torch.Tensor, e1: torch.Tensor, e2: torch.Tensor, ys: torch.Tensor,
                n_theta: int) -> torch.Tensor:
    """(R, nθ) largest horizontal distance from the axis of the points near each ring, per angle bin
    (each bin also sees its two neighbours), 0 where no point is near."""
    rel = points.double() - centre
    a, b = rel @ e1, rel @ e2
    r = torch.sqrt(a * a + b * b)
    step = 2 * math.pi / n_theta
    bins = torch.remainder(torch.round(torch.atan2(b, a) / step).long(), n_theta)
    spacing = float((ys[0] - ys[-1]).abs()) / max(len(ys) - 1, 1)
    out = torch.zeros(len(ys), n_theta, dtype=torch.float64)
    for i, y in enumerate(ys.tolist()):
        near = (points[:, 1].double() - y).abs() <= spacing
        if bool(near.any()):
            out[i].scatter_reduce_(0, bins[near], r[near], "amax")
    return torch.maximum(out, torch.maximum(out.roll(1, 1), out.roll(-1, 1)))


@dataclass(frozen=True)
class RingShape:
    """The shape of a :func:`ring_surface` beyond its rings: radius profile, folds, opening, cap.

    Args:
        min_radius, flare: the radius profile (metres): at least ``min_radius + flare · t`` (t: 0 at
            the top ring, 1 at the bottom).
        folds: ((k, amplitude, phase), ...) vertical folds.
        open_rows: faces between rings ``open_rows`` and below within ``open_halfwidth`` radians of
            the front are left out (a face opening); None: closed. (A ring index, not a height,
            so that every frame of a clip has the same faces.)
        cap: close the top with a fan around one vertex above the first ring.

    Example:
        >>> RingShape(min_radius=0.03, cap=True).flare
        0.0
    """

    min_radius: float = 0.0
    flare: float = 0.0
    folds: tuple = ()
    open_rows: int | None = None
    open_halfwidth: float = 0.0
    cap: bool = False

    def __post_init__(self):
        if not (self.min_radius >= 0 and self.open_halfwidth >= 0):
            raise InputError(f"RingShape: expected min_radius, open_halfwidth >= 0, got {self.min_radius}, "
                             f"{self.open_halfwidth}")
        if any(len(f) != 3 for f in self.folds):
            raise InputError(f"folds: expected (k, amplitude, phase) triples, got {self.folds!r}")


def ring_surface(points: torch.Tensor, centre: torch.Tensor, front: torch.Tensor, y_top: float, y_bottom: float,
                 n_rings: int, n_theta: int, clearance: float, shape: RingShape = RingShape()) -> GarmentPiece:
    """A hanging surface of rings around the vertical axis through ``centre``.

    Ring i (of ``n_rings``, from ``y_top`` down to ``y_bottom``) has, at angle θ (0 at
    ``front``, 90° at front × up, the body's right when it faces ``front``),
    the radius ``max(r_body + clearance, min_radius + flare · t)`` (t: 0 at the top, 1 at
    the bottom; r_body the points' extent near the ring, :func:`_ring_radii`), then the
    running maximum down the rings (hanging), then folds ``Σ a·t·r·(½ + ½ sin(kθ + φ))``
    for ``folds = ((k, a, φ), ...)``, which only push outward.

    Args:
        points: (N, 3) posed body points the surface must enclose (e.g. without the arms).
        centre: (3,) a point of the axis. front: (3,) horizontal direction the body faces.
        y_top, y_bottom: heights of the first and last rings (y_top > y_bottom).
        n_rings, n_theta: grid size (R ≥ 2, nθ ≥ 8).
        clearance: gap to the body (metres).
        shape: a :class:`RingShape`: radius profile, folds, a face opening, a cap.

    Returns:
        :class:`GarmentPiece` with ``uv`` set; the seam column is duplicated (u = 0 and 1).
    """
    check_shape(points, ["N", 3], name="points")
    min_radius, flare, folds, cap = shape.min_radius, shape.flare, shape.folds, shape.cap
    if not y_top > y_bottom or n_rings < 2 or n_theta < 8:
        raise InputError(f"ring_surface: expected y_top > y_bottom, n_rings >= 2, n_theta >= 8; got {y_top}, "
                         f"{y_bottom}, {n_rings}, {n_theta}")
    up = torch.tensor([0.0, 1.0, 0.0], dtype=torch.float64)
    e1 = front.double() - (front.double() @ up) * up
    e1 = e1 / e1.norm().clamp_min(1e-9)
    e2 = torch.linalg.cross(e1, up)  # θ = 90°: the body's right
    c = centre.double().clone()
    ys = torch.linspace(float(y_top), float(y_bottom), int(n_rings), dtype=torch.float64)
    t = torch.linspace(0.0, 1.0, int(n_rings), dtype=torch.float64)[:, None]
    rb = _ring_radii(points, c, e1, e2, ys, n_theta)
    r = torch.maximum(torch.where(rb > 0, rb + clearance, torch.zeros_like(rb)), min_radius + flare * t)
    r = torch.cummax(r, dim=0).values
    theta = torch.arange(n_theta, dtype=torch.float64) * (2 * math.pi / n_theta)
    for k, amp, phase in folds:
        r = r * (1 + amp * t * (0.5 + 0.5 * torch.sin(k * theta + phase)))
    # Vertices: R rings of nθ + 1 (the seam duplicated), (R, nθ+1, 3).
    th = torch.cat([theta, theta[:1] + 2 * math.pi])
    rr = torch.cat([r, r[:, :1]], dim=1)
    dirs = torch.cos(th)[:, None] * e1 + torch.sin(th)[:, None] * e2  # (nθ+1, 3)
    pos = c[None, None] * torch.tensor([1.0, 0.0, 1.0], dtype=torch.float64) + rr[..., None] * dirs[None]
    pos[..., 1] = ys[:, None]
    m = n_theta + 1
    faces = _grid_faces(n_rings, n_theta, shape.open_rows, shape.open_halfwidth)
    verts = pos.reshape(-1, 3)
    u = (th / (2 * math.pi))[None].expand(n_rings, -1)
    v = (1 - t).expand(-1, m)
    uv = torch.stack([u, v], -1).reshape(-1, 2)
    faces = _outward(verts, faces, c)
    if cap:
        top = c.clone()
        top[1] = float(y_top) + 0.3 * float(r[0].mean())  # a low dome over the first ring
        fan = torch.stack([torch.full((n_theta,), verts.shape[0]), torch.arange(n_theta) + 1, torch.arange(n_theta)],
                          -1)
        verts = torch.cat([verts, top[None]])
        uv = torch.cat([uv, torch.tensor([[0.5, 1.0]], dtype=torch.float64)])
        e1_, e2_ = verts[fan[0, 1]] - verts[fan[0, 0]], verts[fan[0, 2]] - verts[fan[0, 0]]
        faces = torch.cat([faces, fan if float(torch.linalg.cross(e1_, e2_)[1]) > 0 else fan[:, [0, 2, 1]]])
    # Normals as if the seam were joined: duplicated seam vertices take the same normal.
    join = torch.arange(verts.shape[0])
    seam = torch.arange(n_rings) * m + n_theta
    join[seam] = seam - n_theta
    nrm = vertex_normals(verts.float(), join[faces])
    nrm = nrm[join]
    used, faces = torch.unique(faces, return_inverse=True)  # drop the vertices an opening left unused
    return GarmentPiece(verts[used].float(), nrm[used], faces.reshape(-1, 3), uv=uv[used].float())


def _grid_faces(n_rings: int, n_theta: int, open_rows: int | None, open_halfwidth: float) -> torch.Tensor:
    """(Fg, 3) two triangles per quad of an (R, nθ + 1) ring grid, less the front opening's quads."""
    m = n_theta + 1
    ii, jj = torch.meshgrid(torch.arange(n_rings - 1), torch.arange(n_theta), indexing="ij")
    a0, a1 = ii * m + jj, ii * m + jj + 1
    b0, b1 = a0 + m, a1 + m
    keep = torch.ones_like(ii, dtype=torch.bool)
    if open_rows is not None:
        theta = torch.arange(n_theta, dtype=torch.float64) * (2 * math.pi / n_theta)
        mid = torch.remainder(theta + math.pi / n_theta + math.pi, 2 * math.pi) - math.pi  # face centre angle
        below = torch.arange(n_rings - 1) >= int(open_rows)
        keep = ~(below[:, None] & (mid.abs() < open_halfwidth)[None])
    quads = torch.stack([a0, a1, b0, b1], -1)[keep]  # (Q, 4)
    return torch.cat([quads[:, [0, 2, 1]], quads[:, [1, 2, 3]]])


def _outward(verts: torch.Tensor, faces: torch.Tensor, centre: torch.Tensor) -> torch.Tensor:
    """Flip the winding if the faces' normals point toward the axis on the whole."""
    v0, v1, v2 = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    fn = torch.linalg.cross(v1 - v0, v2 - v0)
    out = (v0 + v1 + v2) / 3 - centre
    out[:, 1] = 0.0
    return faces if float((fn * out).sum()) >= 0 else faces[:, [0, 2, 1]]


def hem_field(faces: torch.Tensor, verts: torch.Tensor, reach: float = 5.0) -> torch.Tensor:
    """(Vg,) a field on a piece that is 0 on its open border and rises inward to 1: the distance of every
    vertex to the border (its vertices and edge midpoints) in units of ``reach`` times the border's median
    edge length, clipped at 1 (coincident vertices, such as a ring's seam, are one). Its iso-lines inside the
    border are offset curves of the border, on which the stair-steps of a border that follows face edges are
    rounded off (an offset of a zig-zag by more than its depth is a row of wide arcs); a piece without a
    border is 1 everywhere.

    Args:
        faces: (Fg, 3) the piece's faces. verts: (Vg, 3) its positions (e.g. at rest).
        reach: the distance at which the field reaches 1, in border edge lengths.
    """
    check_shape(faces, ["F", 3], name="faces")
    n_verts = check_shape(verts, ["V", 3], name="verts")["V"]
    _, weld = torch.unique((verts.double() * 1e6).round(), dim=0, return_inverse=True)  # a ring's seam is no border
    e = weld[torch.cat([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])]
    key = torch.minimum(e[:, 0], e[:, 1]) * n_verts + torch.maximum(e[:, 0], e[:, 1])
    uniq, count = torch.unique(key, return_counts=True)
    b = uniq[count == 1]
    if len(b) == 0:
        return torch.ones(n_verts)
    p = verts.double()
    first = torch.zeros(n_verts, dtype=torch.int64).scatter_(0, weld, torch.arange(n_verts))
    ba, bb = p[first[b // n_verts]], p[first[b % n_verts]]
    scale = reach * float((ba - bb).norm(dim=1).median())
    dist = torch.cdist(p, torch.cat([ba, bb, (ba + bb) / 2]), compute_mode="donot_use_mm_for_euclid_dist").amin(1)
    return (dist / max(scale, 1e-9)).clamp_max(1.0).float()


def iso_clip(faces: torch.Tensor, corner_field: torch.Tensor, level: float, n_verts: int) -> tuple:
    """Cut triangles along the iso-line ``field = level``, keeping the side where ``field >= level``.

    Faces wholly inside are kept as they are (in their order, first); faces wholly outside are dropped;
    a face the line crosses keeps its inside part, as one or two triangles (same winding) whose new
    corners lie on its crossed edges. New vertices are numbered from ``n_verts`` on, one per crossed
    edge (shared by the faces on both sides of it). Call it again with another index array of the same
    faces (e.g. UV faces) and the same ``corner_field`` for a matching cut of that array.

    Args:
        faces: (F, 3) int64 indices. corner_field: (F, 3) the field at each face corner.
        level: the iso-value. n_verts: the number of vertices ``faces`` indexes.

    Returns:
        (faces (F', 3) int64, edges (E, 2) int64 the end vertices of each new vertex,
        t (E,) float32 its position along the edge: vertex = (1 − t) · v[edges[:, 0]] + t · v[edges[:, 1]]).
    """
    check_shape(faces, ["F", 3], name="faces")
    check_shape(corner_field, [faces.shape[0], 3], name="corner_field")
    inside = corner_field >= level
    k = inside.sum(1)
    cut = (k == 1) | (k == 2)
    f, fld, ins = faces[cut], corner_field[cut].double(), inside[cut]
    # Rotate each cut face so that its odd corner (the one alone on its side) comes first.
    odd = torch.where(k[cut] == 1, ins.long().argmax(1), (~ins).long().argmax(1))
    rot = (odd[:, None] + torch.arange(3)) % 3
    f, fld = f.gather(1, rot), fld.gather(1, rot)

    def crossing(a: int, b: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        t = (level - fld[:, a]) / (fld[:, b] - fld[:, a])
        lo = f[:, a] <= f[:, b]
        return (torch.where(lo, f[:, a], f[:, b]), torch.where(lo, f[:, b], f[:, a]),
                torch.where(lo, t, 1 - t))

    (a0, a1, ta), (b0, b1, tb) = crossing(0, 1), crossing(0, 2)
    key = torch.cat([a0, b0]) * n_verts + torch.cat([a1, b1])
    uniq, inv = torch.unique(key, return_inverse=True)
    t_all = torch.cat([ta, tb])
    t = torch.zeros(len(uniq), dtype=torch.float64).scatter_(0, inv, t_all)
    edges = torch.stack([uniq // n_verts, uniq % n_verts], 1)
    n = len(f)
    x01, x02 = inv[:n] + n_verts, inv[n:] + n_verts
    one = k[cut] == 1  # the odd corner is the inside one: the triangle (c0, x01, x02)
    tri1 = torch.stack([f[:, 0], x01, x02], 1)[one]
    two = ~one  # the odd corner is outside: the quad x01, c1, c2, x02
    q = torch.stack([x01, f[:, 1], f[:, 2], x02], 1)[two]
    out = torch.cat([faces[k == 3], tri1, q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    return out, edges, t.float().clamp(0.0, 1.0)
