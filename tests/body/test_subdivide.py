"""One step of midpoint subdivision: topology, winding, values at the midpoints."""

import pytest
import torch
import trimesh

from relightnet.body.subdivide import midpoint_values, subdivide_faces
from relightnet.checks import InputError, ShapeError


def _normals(v, f):
    return torch.linalg.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])


def test_selected_faces_split_in_four_in_place():
    m = trimesh.creation.icosphere(subdivisions=1)
    v, f = torch.tensor(m.vertices, dtype=torch.float64), torch.tensor(m.faces)
    sel = torch.zeros(len(f), dtype=torch.bool)
    sel[::3] = True
    sub = subdivide_faces(f, len(v), sel)
    assert sub.faces.shape == (len(f) + 3 * int(sel.sum()), 3) and sub.parent.shape == (len(sub.faces),)
    # One new vertex per distinct edge of the selected faces.
    e = torch.cat([f[sel][:, [0, 1]], f[sel][:, [1, 2]], f[sel][:, [2, 0]]]).sort(1).values
    assert sub.edges.shape == (len(torch.unique(e, dim=0)), 2) and (sub.edges[:, 0] < sub.edges[:, 1]).all()
    vm = midpoint_values(v, sub.edges)
    assert vm.shape == (len(v) + len(sub.edges), 3)
    torch.testing.assert_close(vm[len(v):], (v[sub.edges[:, 0]] + v[sub.edges[:, 1]]) / 2, rtol=0, atol=0)
    # Unselected faces keep their order; each selected one becomes four consecutive children that tile it
    # (areas add up, winding kept: every child's normal points like its parent's).
    assert torch.equal(sub.faces[~sel[sub.parent]], f[~sel])
    n_child, n_parent = _normals(vm, sub.faces), _normals(v, f)[sub.parent]
    assert ((n_child * n_parent).sum(1) > 0).all()
    area = torch.zeros(len(f), dtype=torch.float64).index_add_(0, sub.parent, n_child.norm(dim=1))
    torch.testing.assert_close(area, _normals(v, f).norm(dim=1), rtol=1e-12, atol=0)
    torch.testing.assert_close(n_child.norm(dim=1), n_parent.norm(dim=1) / torch.where(sel[sub.parent], 4, 1),
                               rtol=1e-12, atol=0)
    # The midpoint rows name the vertices that follow the originals.
    mid = sub.midpoints
    assert torch.equal(mid[:, 0], torch.arange(len(sub.edges)) + len(v)) and torch.equal(mid[:, 1:], sub.edges)
    # A closed selection stays closed: every edge of the whole subdivided sphere is shared by two faces.
    full = subdivide_faces(f, len(v), torch.ones(len(f), dtype=torch.bool)).faces
    _, counts = torch.unique(torch.cat([full[:, [0, 1]], full[:, [1, 2]], full[:, [2, 0]]]).sort(1).values, dim=0,
                             return_counts=True)
    assert (counts == 2).all()


def test_unit_midpoints_and_frames():
    f = torch.tensor([[0, 1, 2]])
    n = torch.tensor([[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]]).expand(2, 3, 3)  # (T, V, 3)
    sub = subdivide_faces(f, 3, torch.tensor([True]))
    out = midpoint_values(n, sub.edges, unit=True)
    assert out.shape == (2, 6, 3)
    torch.testing.assert_close(out[:, 3:].norm(dim=-1), torch.ones(2, 3))
    torch.testing.assert_close(out[0, 3], torch.tensor([1.0, 1.0, 0.0]) / 2**0.5)


def test_bad_inputs_raise():
    f = torch.tensor([[0, 1, 2]])
    with pytest.raises(InputError, match="faces"):
        subdivide_faces(f, 2, torch.tensor([True]))
    with pytest.raises(ShapeError, match="select"):
        subdivide_faces(f, 3, torch.tensor([True, False]))
    with pytest.raises(ShapeError, match="edges"):
        midpoint_values(torch.zeros(3, 3), torch.zeros(2, 3, dtype=torch.int64))
