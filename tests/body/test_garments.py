"""Garment geometry primitives: offset shells and hanging ring surfaces, on the real Anny body."""

import math

import numpy as np
import pytest
import torch

from relightnet.body.albedo import REGIONS, region_labels
from relightnet.body.garments import RingShape, hem_field, iso_clip, radial_directions, ring_surface, shell_surface
from relightnet.checks import InputError


@pytest.fixture(scope="module")
def posed(anny_body):
    pose = anny_body.pose("arms_down")
    pose[0, anny_body.joint_index("upperleg01.L")] = torch.tensor([-0.5, 0.0, 0.0])  # a step forward
    with torch.no_grad():
        out = anny_body(pose=pose)
    return out.verts[0], out.normals[0], out.joints[0]


def test_shell_follows_its_body_vertices(anny_body, posed):
    verts, normals, _ = posed
    faces = anny_body.faces
    top = region_labels(anny_body, "long", "long") == REGIONS.index("top")
    fsel = top[faces].all(1)
    off = torch.full((len(verts),), 0.02)
    piece = shell_surface(verts, normals, faces, fsel, off, sag=0.0)
    assert piece.faces.shape == (int(fsel.sum()), 3) and piece.source_faces.shape == (int(fsel.sum()),)
    assert torch.equal(piece.source[piece.faces], faces[piece.source_faces])  # same triangles, reindexed
    d = piece.verts - verts[piece.source]
    torch.testing.assert_close(d, 0.02 * normals[piece.source], atol=1e-6, rtol=0)
    assert torch.allclose(piece.normals.norm(dim=1), torch.ones(len(piece.verts)), atol=1e-5)
    # Outward like the body: the shell's normals agree with the body's at the same vertices.
    assert (piece.normals * normals[piece.source]).sum(1).mean() > 0.9
    # Sag only moves vertices whose normal points down, and only downward.
    sagged = shell_surface(verts, normals, faces, fsel, off, sag=0.05)
    dy = (sagged.verts - piece.verts)[:, 1]
    assert (dy <= 1e-7).all() and (dy < -1e-3).any()
    assert torch.equal(dy < -1e-6, (normals[piece.source][:, 1] < -2e-5) & (dy < -1e-6))
    with pytest.raises(InputError, match="face_sel"):
        shell_surface(verts, normals, faces, torch.zeros(len(faces), dtype=torch.bool), off)


def test_radial_directions_point_away_from_the_axis():
    a, b = torch.tensor([0.0, 1.0, 0.0]), torch.tensor([0.0, 0.0, 0.0])
    p = torch.tensor([[0.3, 0.5, 0.0], [0.0, 0.2, -0.1], [0.1, 1.5, 0.0]])
    d = radial_directions(p, a, b)
    torch.testing.assert_close(d[:2], torch.tensor([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]))
    torch.testing.assert_close(d[2].norm(), torch.tensor(1.0))  # beyond the end: from the end point


def test_ring_surface_encloses_the_body_and_hangs(anny_body, posed):
    verts, _, joints = posed
    root = joints[anny_body.joint_index("root")]
    front = torch.tensor([0.0, 0.0, 1.0])
    y0, y1, clearance = float(root[1]) + 0.05, float(root[1]) - 0.55, 0.015
    piece = ring_surface(verts, root, front, y0, y1, 25, 48, clearance, shape=RingShape(flare=0.05))
    assert piece.verts.shape == (25 * 49, 3) and piece.faces.shape == (2 * 24 * 48, 3)
    assert piece.uv.shape == (25 * 49, 2)
    assert float(piece.uv.min()) >= 0 and float(piece.uv.max()) <= 1
    assert torch.allclose(piece.normals.norm(dim=1), torch.ones(len(piece.verts)), atol=1e-5)
    c = root.double().numpy()
    rel_v = piece.verts.double().numpy() - c
    assert (piece.normals.double().numpy()[:, [0, 2]] * rel_v[:, [0, 2]]).sum(1).mean() > 0  # outward
    # Every body point between two rings lies inside the surface, clearance and all: the radius at
    # its angle (rings interpolated) exceeds its own distance from the axis.
    r = np.hypot(rel_v[:, 0], rel_v[:, 2]).reshape(25, 49)[:, :48]
    p = verts.double().numpy() - c
    inside = (p[:, 1] + c[1] < y0) & (p[:, 1] + c[1] > y1)
    p = p[inside]
    ang = np.mod(np.arctan2(-p[:, 0], p[:, 2]), 2 * math.pi)  # θ from front (+z) toward front × up (−x)
    j = np.minimum((ang / (2 * math.pi / 48)).astype(int), 47)
    t = (y0 - (p[:, 1] + c[1])) / (y0 - y1) * 24
    i = np.minimum(t.astype(int), 23)
    radius = np.minimum.reduce([r[i, j], r[i + 1, j], r[i, (j + 1) % 48], r[i + 1, (j + 1) % 48]])
    assert (np.hypot(p[:, 0], p[:, 2]) < radius - 0.5 * clearance).all()
    # Hanging: the radius never shrinks going down, at any angle.
    assert (np.diff(r, axis=0) >= -1e-6).all()


def test_ring_surface_opening_and_cap(anny_body, posed):
    verts, _, joints = posed
    head = joints[anny_body.joint_index("head")]
    front = torch.tensor([0.0, 0.0, 1.0])
    top = float(verts[:, 1].max())
    closed = ring_surface(verts, head, front, top + 0.02, top - 0.4, 12, 40, 0.02,
                          shape=RingShape(min_radius=0.03, cap=True))
    opened = ring_surface(verts, head, front, top + 0.02, top - 0.4, 12, 40, 0.02,
                          shape=RingShape(min_radius=0.03, cap=True, open_rows=4, open_halfwidth=math.radians(60)))
    assert closed.faces.shape[0] == 2 * 11 * 40 + 40
    removed = closed.faces.shape[0] - opened.faces.shape[0]
    assert removed > 0 and removed % 2 == 0
    # The opening faces the front: no face centre of the opened rows lies within 50° of +z.
    v = opened.verts.double()
    cen = v[opened.faces].mean(1) - head.double()
    low = cen[:, 1] + float(head[1]) < top + 0.02 - 4.5 * (0.42 / 11)
    ang = torch.atan2(cen[:, 0], cen[:, 2]).abs()
    assert not bool((low & (ang < math.radians(50))).any())
    # The cap closes the top above the first ring, facing up (its normal and its winding).
    assert float(closed.verts[:, 1].max()) > top + 0.02
    cap = closed.faces[-40:]
    v = closed.verts
    assert (torch.linalg.cross(v[cap[:, 1]] - v[cap[:, 0]], v[cap[:, 2]] - v[cap[:, 0]])[:, 1] > 0).all()
    assert float(closed.normals[-1, 1]) > 0.99
    with pytest.raises(InputError, match="ring_surface"):
        ring_surface(verts, head, front, 1.0, 1.2, 12, 40, 0.02)


def _grid(n: int = 9) -> tuple[torch.Tensor, torch.Tensor]:
    """An n × n vertex grid on [0, 1]² (z = 0) in counter-clockwise triangles."""
    y, x = torch.meshgrid(torch.linspace(0, 1, n), torch.linspace(0, 1, n), indexing="ij")
    verts = torch.stack([x.flatten(), y.flatten(), torch.zeros(n * n)], 1)
    i, j = torch.meshgrid(torch.arange(n - 1), torch.arange(n - 1), indexing="ij")
    a = (i * n + j).flatten()
    faces = torch.cat([torch.stack([a, a + 1, a + n + 1], 1), torch.stack([a, a + n + 1, a + n], 1)])
    return verts, faces


def _area(v: torch.Tensor, f: torch.Tensor) -> torch.Tensor:
    """(F,) signed area of planar triangles (z = 0), positive counter-clockwise."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def test_iso_clip_cuts_along_the_iso_line_through_triangles():
    verts, faces = _grid()
    # A line oblique to every edge: field = x + 0.37 y, kept where >= 0.61.
    field = verts[:, 0] + 0.37 * verts[:, 1]
    out, edges, t = iso_clip(faces, field[faces], 0.61, len(verts))
    v = torch.cat([verts, (1 - t[:, None]) * verts[edges[:, 0]] + t[:, None] * verts[edges[:, 1]]])
    new = v[len(verts):]
    assert len(new) > 8 and torch.allclose(new[:, 0] + 0.37 * new[:, 1], torch.full((len(new),), 0.61), atol=1e-6)
    # The kept part: the faces wholly inside first and unchanged, same winding, exactly the area on the kept side.
    whole = (field[faces] >= 0.61).all(1)
    assert torch.equal(out[: int(whole.sum())], faces[whole])
    area = _area(v, out)
    assert float(area.min()) > 0
    # The region x + 0.37 y >= 0.61 of the unit square: 1 minus the triangle-trapezoid left of the line.
    kept = 1 - (0.61 - 0.37 / 2)  # the line crosses every row at x = 0.61 − 0.37 y, 0 <= x <= 1 for y in [0, 1]
    assert abs(float(area.sum()) - kept) < 1e-6
    # A new vertex inside the square is shared by the faces on both sides of its edge: the cut mesh stays connected.
    uses = torch.bincount(out.flatten(), minlength=len(v))[len(verts):]
    inner = (new[:, :2] > 1e-6).all(1) & (new[:, :2] < 1 - 1e-6).all(1)
    assert int(uses[inner].min()) >= 2 and int(uses[~inner].min()) >= 1


def test_hem_field_is_zero_on_the_border_and_one_inside():
    verts, faces = _grid(11)
    g = hem_field(faces, verts, reach=2.0)
    on_border = (verts[:, 0] % 1 == 0) | (verts[:, 1] % 1 == 0)
    assert float(g[on_border].abs().max()) == 0.0
    # The distance to the border in units of 2 border edges (0.1 each), clipped at 1.
    d = torch.stack([verts[:, 0], 1 - verts[:, 0], verts[:, 1], 1 - verts[:, 1]]).amin(0)
    assert torch.allclose(g, (d / 0.2).clamp_max(1.0), atol=1e-6)
    # A closed surface has no border (a seam of coincident vertices is none either): 1 everywhere.
    ring = ring_surface(torch.randn(200, 3) * 0.1, torch.zeros(3), torch.tensor([0.0, 0.0, 1.0]), 0.3, -0.3, 6, 16,
                        0.01, shape=RingShape(cap=True))
    g = hem_field(ring.faces, ring.verts)
    bottom = ring.verts[:, 1] < -0.29
    assert float(g[bottom].max()) < 1e-6 and float(g[~bottom].min()) > 0.1  # the seam column is no border
