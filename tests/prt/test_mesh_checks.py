"""relightnet.prt.mesh_checks: meshes and normals validated before ray casting, errors naming the input."""

import warnings

import numpy as np
import pytest
import torch
import trimesh

from relightnet.checks import InputError, ShapeError
from relightnet.prt import check_mesh
from relightnet.prt.mesh_checks import MeshWarning, check_normals, mesh_scale, nonmanifold_edge_count


def _box():
    m = trimesh.creation.box(extents=(1.0, 2.0, 2.0))
    return np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int32)


def test_a_good_mesh_comes_back_as_float32_and_int64():
    v, f = _box()
    verts, faces = check_mesh(v, f)
    assert verts.dtype == torch.float32 and faces.dtype == torch.int64 and faces.shape == (12, 3)
    assert mesh_scale(verts) == pytest.approx(3.0)  # the box diagonal sqrt(1 + 4 + 4)
    assert nonmanifold_edge_count(faces) == 0


def test_non_manifold_edges_warn_or_fail():
    v, f = _box()
    f2 = np.concatenate([f, f[:2]])  # two faces duplicated: their edges are shared by 3 or more faces
    assert nonmanifold_edge_count(torch.as_tensor(f2)) > 0
    with pytest.warns(MeshWarning, match="non-manifold"):
        check_mesh(v, f2)
    with pytest.raises(InputError, match="non-manifold"):
        check_mesh(v, f2, manifold="error")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_mesh(v, f2, manifold="ignore")


@pytest.mark.parametrize("verts, faces, error, message", [
    (np.zeros((0, 3)), np.zeros((0, 3), int), InputError, "mesh is empty"),
    (np.zeros((4, 2)), np.zeros((1, 3), int), ShapeError, "verts"),
    (np.eye(3), np.array([[0, 1, 3]]), InputError, r"indices must lie in \[0, 2\], found range \[0, 3\]"),
    (np.eye(3), np.array([[0.0, 1.0, 2.0]]), InputError, "faces: expected an integer dtype"),
    (np.array([[0, 0, 0], [1, 0, 0], [np.nan, 0, 0]]), np.array([[0, 1, 2]]), InputError, "NaN"),
    (np.ones((3, 3)), np.array([[0, 1, 2]]), InputError, "all vertices coincide"),
])
def test_bad_meshes(verts, faces, error, message):
    with pytest.raises(error, match=message):
        check_mesh(verts, faces)


def test_normals_must_be_unit_and_one_per_vertex():
    n = torch.nn.functional.normalize(torch.randn(5, 3), dim=-1).double()
    out = check_normals(n, 5)
    assert out.dtype == torch.float32 and torch.allclose(out.double(), n, atol=1e-6)
    with pytest.raises(ShapeError, match="normals"):
        check_normals(n, 4)
    with pytest.raises(InputError, match="unit"):
        check_normals(n * 2, 5)
    with pytest.raises(InputError, match="floating"):
        check_normals(torch.ones(5, 3, dtype=torch.int64), 5)
