"""Shoes as geometry: a closed shell around a foot with a toe box, a heel, a collar and a flat sole.

:func:`shoe_surface` builds one shoe around the rest-pose points of one foot. The foot axis runs
horizontally from the heel to the toes; along it, rings of ``n_theta`` vertices enclose the
foot's cross-section near each ring, every ring a convex polygon around the section's centre
whose edges stay outside the section's convex hull (the support of the points in each direction,
:func:`_ring_radii`) plus a clearance, so no foot point between the sole and the collar pokes
through. Below the lowest foot point the rings are flattened onto one plane ``sole`` metres lower:
a flat sole slab under the whole foot. The toe end runs ``toe_room`` past the toes and both ends are
closed by a dome (the toe box, the heel), so the shoe is a closed surface; the leg enters it
through the top at the collar. The UV coordinates are (s, h): s from the heel (0) to the toe (1),
h the height from the sole's bottom (0) to the collar (1), so a texture painted in rows of
height puts a sole band, a welt and an upper where they belong on every shoe.

:data:`SHOE_KINDS` are the shapes the avatar's outfits wear (collar height above the ankle joint,
sole thickness, clearance, toe room). Posing is the caller's: the avatar's shoes follow the foot,
toe and lower-leg bones (:mod:`relightnet.pipeline.outfits`).

Shapes: N points; a shoe has Vs = n_rings · n_theta + 2 vertices. World frame: y up.
"""

from __future__ import annotations

import math

import torch

from ..checks import InputError, check_shape
from .base import vertex_normals
from .garments import GarmentPiece

__all__ = ["SHOE_KINDS", "shoe_surface"]

#: Shoe shapes (metres): collar above the ankle joint, sole thickness, clearance to the foot, toe room.
SHOE_KINDS = {
    "sneaker": {"collar": -0.005, "sole": 0.022, "clearance": 0.009, "toe_room": 0.018},
    "boot": {"collar": 0.1, "sole": 0.025, "clearance": 0.011, "toe_room": 0.016},
    "dress_shoe": {"collar": -0.02, "sole": 0.012, "clearance": 0.007, "toe_room": 0.03},
    "flat": {"collar": -0.035, "sole": 0.008, "clearance": 0.006, "toe_room": 0.012},
}


def _ring_radii(sec: torch.Tensor, n_theta: int) -> torch.Tensor:
    """(nθ,) vertex radii of a polygon around the origin enclosing the 2D points ``sec`` (P, 2): with
    h(θ) the points' support, vertex j at max(h_{j−1}, h_j, h_{j+1}) / cos²(Δ/2) puts every edge outside
    their convex hull (the hull's support midway between two directions is at most max(h_j, h_{j+1}) / cos(Δ/2))."""
    theta = torch.arange(n_theta, dtype=torch.float64) * (2 * math.pi / n_theta)
    d = torch.stack([torch.cos(theta), torch.sin(theta)], 1)  # θ = 0: up, 90°: lateral
    h = (sec @ d.T).amax(0).clamp_min(0.0)
    h = torch.maximum(h, torch.maximum(h.roll(1), h.roll(-1)))
    return h / math.cos(math.pi / n_theta) ** 2


def _sections(s: torch.Tensor, uv: torch.Tensor, ss: torch.Tensor, n_theta: int) -> tuple:
    """Per ring at ss (R,): the (R, 2) centre (height, lateral) and (R, nθ) radii of the points whose
    axial coordinate ``s`` lies within one ring spacing; rings without points copy the nearest one."""
    sp = float(ss[1] - ss[0])
    R = len(ss)
    centre = torch.full((R, 2), math.nan, dtype=torch.float64)
    radii = torch.zeros(R, n_theta, dtype=torch.float64)
    for i in range(R):
        near = (s - ss[i]).abs() <= sp
        if int(near.sum()) < 3:
            continue
        sec = uv[near]
        centre[i] = (sec.amin(0) + sec.amax(0)) / 2
        radii[i] = _ring_radii(sec - centre[i], n_theta)
    have = torch.nonzero(~torch.isnan(centre[:, 0])).flatten()
    if len(have) == 0:
        raise InputError("shoe_surface: no foot points along the foot axis")
    nearest = have[(torch.arange(R)[:, None] - have[None]).abs().argmin(1)]
    return centre[nearest], radii[nearest]


def _tube_faces(n_rings: int, n_theta: int) -> torch.Tensor:
    """(Fs, 3) faces of R closed rings of nθ vertices joined in order, plus a fan at each end (end vertices
    R·nθ at the first ring and R·nθ + 1 at the last)."""
    i, j = torch.meshgrid(torch.arange(n_rings - 1), torch.arange(n_theta), indexing="ij")
    a0, a1 = i * n_theta + j, i * n_theta + (j + 1) % n_theta
    b0, b1 = a0 + n_theta, a1 + n_theta
    quads = torch.stack([a0, a1, b0, b1], -1).reshape(-1, 4)
    k = torch.arange(n_theta)
    first = torch.stack([torch.full_like(k, n_rings * n_theta), (k + 1) % n_theta, k], -1)
    last = (n_rings - 1) * n_theta
    end = torch.stack([torch.full_like(k, n_rings * n_theta + 1), last + k, last + (k + 1) % n_theta], -1)
    return torch.cat([quads[:, [0, 1, 2]], quads[:, [1, 3, 2]], first, end])


def shoe_surface(points: torch.Tensor, ankle: torch.Tensor, toe: torch.Tensor, kind: str = "sneaker",
                 n_rings: int = 22, n_theta: int = 24) -> GarmentPiece:
    """A closed shoe around one foot (module docstring).

    Args:
        points: (N, 3) rest-pose points of the foot and lower leg (those above the collar are ignored).
        ankle: (3,) the ankle joint. toe: (3,) the toes' base joint (the foot axis is ankle → toe, horizontal).
        kind: one of :data:`SHOE_KINDS`. n_rings, n_theta: grid size (R ≥ 4, nθ ≥ 8).

    Returns:
        :class:`~relightnet.body.garments.GarmentPiece` (Vs vertices, faces wound outward) with ``uv``
        (s along the foot, h up the shoe).
    """
    check_shape(points, ["N", 3], name="points")
    if kind not in SHOE_KINDS or n_rings < 4 or n_theta < 8:
        raise InputError(f"shoe_surface: expected a kind of {sorted(SHOE_KINDS)}, n_rings >= 4, n_theta >= 8; "
                         f"got {kind!r}, {n_rings}, {n_theta}")
    k = SHOE_KINDS[kind]
    ankle, toe = ankle.double(), toe.double()
    up = torch.tensor([0.0, 1.0, 0.0], dtype=torch.float64)
    ax = toe - ankle
    ax[1] = 0.0
    ax = ax / ax.norm().clamp_min(1e-9)
    lat = torch.linalg.cross(ax, up)
    top = float(ankle[1]) + k["collar"]
    p = points.double()
    p = p[p[:, 1] <= top]
    if len(p) < 8:
        raise InputError(f"shoe_surface: fewer than 8 foot points below the collar at y = {top:.3f}")
    rel = p - ankle
    s, hl = rel @ ax, torch.stack([rel @ up, rel @ lat], 1)
    c = k["clearance"]
    ss = torch.linspace(float(s.min()) - 0.5 * c, float(s.max()) + k["toe_room"], n_rings, dtype=torch.float64)
    centre, radii = _sections(s, hl, ss, n_theta)
    radii = radii + c
    theta = torch.arange(n_theta, dtype=torch.float64) * (2 * math.pi / n_theta)
    hh = centre[:, :1] + radii * torch.cos(theta)  # (R, nθ) height and lateral offsets from the ankle
    ll = centre[:, 1:] + radii * torch.sin(theta)
    floor = float(p[:, 1].min()) - float(ankle[1])
    hh = torch.where(hh < floor, torch.full_like(hh, floor - k["sole"]), hh)  # the flat sole
    hh = hh.clamp_max(top - float(ankle[1]) + c)
    ring = ankle + ss[:, None, None] * ax + hh[..., None] * up + ll[..., None] * lat
    ends = []
    for i, sign in ((0, -1.0), (n_rings - 1, 1.0)):  # dome caps: heel and toe box
        e = ring[i].mean(0) + sign * (0.35 if sign > 0 else 0.2) * float(radii[i].mean()) * ax
        e[1] = max(float(e[1]), float(ankle[1]) + floor - k["sole"])
        ends.append(e)
    verts = torch.cat([ring.reshape(-1, 3), torch.stack(ends)])
    faces = _tube_faces(n_rings, n_theta)
    v0, v1, v2 = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    if float((torch.linalg.cross(v1 - v0, v2 - v0) * v0).sum()) < 0:  # signed volume: wind outward
        faces = faces[:, [0, 2, 1]]
    y0 = float(ankle[1]) + floor - k["sole"]
    u = ((verts - ankle) @ ax - ss[0]) / float(ss[-1] - ss[0] + 1e-9)
    h = (verts[:, 1] - y0) / max(top + c - y0, 1e-6)
    uv = torch.stack([u.clamp(0, 1), h.clamp(0, 1)], 1).float()
    vf = verts.float()
    return GarmentPiece(vf, vertex_normals(vf, faces), faces, uv=uv)
