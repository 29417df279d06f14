"""Transport of a once-subdivided mesh with midpoints ray cast only at shadow edges, against direct ray casting."""

import math

import numpy as np
import pytest
import torch
import trimesh

from relightnet.body.subdivide import midpoint_values, subdivide_faces
from relightnet.checks import InputError, ShapeError
from relightnet.prt import PrtSettings, refined_transport, transport_directions, vertex_transport
from relightnet.prt.refine import SHADOW_EDGE
from relightnet.sh import light_to_world, sh_basis

Y0 = 0.5 / math.sqrt(math.pi)
EPS32 = float(np.finfo(np.float32).eps)


def _scene(n=25):
    """A ball (r 0.3) 0.45 above a 2 m × 2 m ground grid of n × n vertices, the grid subdivided once."""
    ico = trimesh.creation.icosphere(subdivisions=2, radius=0.3)
    sv = torch.tensor(ico.vertices, dtype=torch.float32) + torch.tensor([0.1, 0.45, 0.0])
    sn = torch.nn.functional.normalize(torch.tensor(ico.vertices, dtype=torch.float32), dim=1)
    g = torch.linspace(-1.0, 1.0, n)
    X, Z = torch.meshgrid(g, g, indexing="xy")
    pv = torch.stack([X.flatten(), torch.zeros(n * n), Z.flatten()], 1)
    idx = torch.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].flatten(), idx[:-1, 1:].flatten(), idx[1:, :-1].flatten(), idx[1:, 1:].flatten()
    pf = torch.cat([torch.stack([a, c, b], 1), torch.stack([b, c, d], 1)]) + len(sv)
    v, f = torch.cat([sv, pv]), torch.cat([torch.tensor(ico.faces), pf])
    nrm = torch.cat([sn, torch.tensor([0.0, 1.0, 0.0]).expand(n * n, 3)])
    sub = subdivide_faces(f, len(v), torch.arange(len(f)) >= len(ico.faces))
    return midpoint_values(v, sub.edges), sub.faces, midpoint_values(nrm, sub.edges, unit=True), sub.midpoints


def _atol(n_dirs):
    """Rows computed over other row subsets differ by float32 rounding of a D-term sum (BLAS blocking),
    each term at most w·|Y| ≤ (4π/D)·max|Y_k| ≈ (4π/D)·1.1 for lmax 2."""
    return 4 * n_dirs * EPS32 * (4 * math.pi / n_dirs) * 1.1


def test_cast_rows_equal_direct_ray_casting():
    v, f, n, mid = _scene()
    full = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=128, seed=1))
    T, cast = refined_transport(v, f, n, mid, prt=PrtSettings(n_dirs=128, seed=1), return_cast=True)
    rows = torch.ones(len(v), dtype=torch.bool)
    rows[mid[~cast, 0]] = False  # originals and ray-cast midpoints
    torch.testing.assert_close(T[rows], full[rows], rtol=0, atol=_atol(128))
    share = float(cast.float().mean())
    assert 0.01 < share < 0.5  # the shadow's rim, not the whole ground
    # With threshold 0 the midpoints left out are those whose endpoints see the same directions: a convex
    # ball's shadow cannot fall between two points that both see past it (or cover both and leave the
    # middle lit), so the estimate is exact there, but for rays grazing the ball's silhouette (tangent
    # within float precision, which Embree may call either way): at most one or two directions per row.
    dirs_l, w = transport_directions(128, 1)
    T0 = refined_transport(v, f, n, mid, prt=PrtSettings(n_dirs=128, seed=1), threshold=0.0)
    err = (T0 - full).abs().max(1).values
    one_dir = float(w.max()) * float(sh_basis(dirs_l, 2).abs().max())
    assert float((err > _atol(128)).float().mean()) < 0.01 and float(err.max()) <= 2 * one_dir
    est = mid[~cast]
    # With the default threshold, a midpoint's estimate is off at most by half of the cosine-weighted
    # share of directions where its endpoints differ (≤ SHADOW_EDGE), in every coefficient.
    cos = (n[est[:, 0]] @ light_to_world(dirs_l).T).clamp_min(0)
    bound = 0.5 * SHADOW_EDGE * (cos * w).sum(1) * sh_basis(dirs_l, 2).abs().max(0).values.max()
    assert ((T[est[:, 0]] - full[est[:, 0]]).abs().max(1).values <= bound + _atol(128)).all()
    assert float((T[est[:, 0]] - full[est[:, 0]]).abs().max()) > 0  # some are estimates, not copies


def test_unshadowed_midpoints_are_the_closed_form_of_their_own_normal():
    ico = trimesh.creation.icosphere(subdivisions=2)
    v, f = torch.tensor(ico.vertices, dtype=torch.float32), torch.tensor(ico.faces)
    sub = subdivide_faces(f, len(v), torch.ones(len(f), dtype=torch.bool))
    vm = midpoint_values(v, sub.edges)
    nm = midpoint_values(v, sub.edges, unit=True)
    T, cast = refined_transport(vm, sub.faces, nm, sub.midpoints, prt=PrtSettings(n_dirs=256), return_cast=True)
    assert not cast.any()  # a convex body casts no shadow on itself
    free = vertex_transport(vm, sub.faces, nm, prt=PrtSettings(n_dirs=256, occlusion=False))
    torch.testing.assert_close(T, free, rtol=0, atol=_atol(256))


def test_bounce_and_vertex_subset():
    v, f, n, mid = _scene(13)
    full = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=64, bounces=1), albedo=0.5)
    T, cast = refined_transport(v, f, n, mid, prt=PrtSettings(n_dirs=64, bounces=1), albedo=0.5, threshold=0.0,
                                return_cast=True)
    # threshold 0: the direct rows are exact (test above, grazing rays aside), so the bounce of every cast
    # vertex is too: rays that hit the ground interpolate the same vertex values.
    rows = torch.ones(len(v), dtype=torch.bool)
    rows[mid[~cast, 0]] = False
    err = (T[rows] - full[rows]).abs().max(1).values
    assert float((err > 4 * _atol(64)).float().mean()) < 0.01
    # A midpoint not cast takes its endpoints' mean bounce on top of its exact direct row.
    direct = refined_transport(v, f, n, mid, prt=PrtSettings(n_dirs=64), threshold=0.0)
    b = T - direct
    e = mid[~cast]
    torch.testing.assert_close(b[e[:, 0]], 0.5 * (b[e[:, 1]] + b[e[:, 2]]), rtol=0, atol=4 * _atol(64))
    # A subset: the same rows bit for bit (one projection over every row, whichever are cast), zeros
    # elsewhere (midpoints wanted pull in their endpoints' rays only).
    alone = refined_transport(v, f, n, mid, prt=PrtSettings(n_dirs=64))
    for want in (torch.cat([mid[::7, 0], torch.tensor([0, 5, len(v) - len(mid) - 1])]), mid[1::3, 0],
                 torch.arange(1, len(v), 5), torch.tensor([len(v) - 1])):
        sub = refined_transport(v, f, n, mid, prt=PrtSettings(n_dirs=64), vertices=want)
        assert torch.equal(sub[want], alone[want])
    rest = torch.ones(len(v), dtype=torch.bool)
    rest[want] = False
    assert (sub[rest] == 0).all()
    # No midpoints: plain vertex_transport.
    none = torch.zeros(0, 3, dtype=torch.int64)
    prt = PrtSettings(n_dirs=64)
    torch.testing.assert_close(refined_transport(v, f, n, none, prt=prt), vertex_transport(v, f, n, prt=prt),
                               rtol=0, atol=_atol(64))


def test_bad_inputs_raise():
    v, f, n, mid = _scene(5)
    with pytest.raises(ShapeError, match="midpoints"):
        refined_transport(v, f, n, mid[:, :2])
    with pytest.raises(InputError, match="midpoints"):
        refined_transport(v, f, n, mid + len(v))
    with pytest.raises(InputError, match="midpoints"):
        refined_transport(v, f, n, torch.cat([mid, mid[:1]]))  # a vertex twice
    with pytest.raises(InputError, match="midpoints"):
        refined_transport(v, f, n, torch.stack([mid[:, 0], mid[:, 0], mid[:, 2]], 1))  # endpoint is a midpoint
    with pytest.raises(InputError, match="threshold"):
        refined_transport(v, f, n, mid, threshold=1.5)
    with pytest.raises(InputError, match="bounces"):
        refined_transport(v, f, n, mid, prt=PrtSettings(bounces=1), vertices=torch.tensor([0]))
