"""relightnet.body.base: vertex normals and rotation vectors shared by every body model."""

import math

import pytest
import torch
import trimesh

from relightnet.body.base import broadcast_batch, compose_rotvecs, matrix_to_rotvec, rotvec_to_matrix, vertex_normals
from relightnet.checks import InputError


def test_vertex_normals_of_a_sphere_point_outward():
    m = trimesh.creation.icosphere(subdivisions=2)
    v, f = torch.tensor(m.vertices, dtype=torch.float64), torch.tensor(m.faces)
    n = vertex_normals(v, f)
    assert n.shape == v.shape and torch.allclose(n.norm(dim=-1), torch.ones(len(v), dtype=v.dtype))
    assert (n * torch.nn.functional.normalize(v, dim=-1)).sum(-1).min() > 0.99
    batched = vertex_normals(torch.stack([v, 2 * v]), f)  # (B, V, 3): scale does not change normals
    assert torch.allclose(batched[0], n) and torch.allclose(batched[1], n)
    lone = vertex_normals(torch.cat([v, torch.zeros(1, 3, dtype=v.dtype)]), f)
    assert lone[-1].abs().max() == 0  # a vertex on no face gets 0


def test_rotation_vectors_round_trip_and_compose():
    g = torch.Generator().manual_seed(0)
    r = torch.randn(50, 3, generator=g, dtype=torch.float64)
    r = r / r.norm(dim=-1, keepdim=True) * torch.rand(50, 1, generator=g, dtype=torch.float64) * 3.0
    R = rotvec_to_matrix(r)
    assert torch.allclose(R @ R.transpose(-1, -2), torch.eye(3, dtype=r.dtype).expand(50, 3, 3), atol=1e-12)
    assert torch.allclose(matrix_to_rotvec(R), r, atol=1e-9)
    quarter = torch.tensor([0.0, math.pi / 2, 0.0], dtype=torch.float64)  # 90° about +y
    assert torch.allclose(compose_rotvecs(quarter, quarter), torch.tensor([0.0, math.pi, 0.0], dtype=torch.float64))
    x = torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64)
    a, b = torch.tensor([0.3, 0.0, 0.0], dtype=torch.float64), quarter
    assert torch.allclose(rotvec_to_matrix(compose_rotvecs(a, b)) @ x, rotvec_to_matrix(b) @ (rotvec_to_matrix(a) @ x))


def test_broadcast_batch():
    assert broadcast_batch({"pose": torch.zeros(3, 5, 3), "shape": torch.zeros(1, 10)}, "anny") == 3
    with pytest.raises(InputError, match="anny: inconsistent batch sizes"):
        broadcast_batch({"pose": torch.zeros(3, 5, 3), "shape": torch.zeros(2, 10)}, "anny")
