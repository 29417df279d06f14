"""Body-test fixtures: a synthetic SMPL-format file (the Anny model is in tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

#: SMPL's kinematic tree (parent of each of the 24 joints).
SMPL_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]


def make_smpl_arrays(n_verts: int = 6890, seed: int = 0) -> dict[str, np.ndarray]:
    """A random-but-valid SMPL model: an ellipsoid 'body' of ``n_verts`` vertices, 24 joints.

    Faces are the convex hull (outward), joints sit inside the ellipsoid along its axis,
    ``J_regressor`` averages the 8 vertices nearest each joint, ``weights`` are a softmax of
    the distances to the joints, ``posedirs``/``shapedirs`` are small random fields.
    """
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(seed)
    i = np.arange(n_verts) + 0.5
    y = 1 - 2 * i / n_verts
    r = np.sqrt(1 - y * y)
    phi = np.pi * (3 - np.sqrt(5)) * i
    unit = np.stack([r * np.cos(phi), y, r * np.sin(phi)], axis=1)
    v = unit * np.array([0.25, 0.85, 0.15]) + np.array([0.0, -0.1, 0.0])
    hull = ConvexHull(v)
    f = hull.simplices.copy()
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    centre = v.mean(0)
    flip = (n * (v[f].mean(1) - centre)).sum(-1) < 0
    f[flip] = f[flip][:, ::-1]
    joints = np.stack([np.zeros(24), np.linspace(-0.6, 0.6, 24), np.zeros(24)], axis=1)
    joints[:, 0] = 0.1 * np.sin(np.arange(24))
    d = np.linalg.norm(v[:, None] - joints[None], axis=-1)
    jreg = np.zeros((24, n_verts))
    for j in range(24):
        jreg[j, np.argsort(d[:, j])[:8]] = 1 / 8
    w = np.exp(-d / 0.05)
    w /= w.sum(1, keepdims=True)
    kintree = np.stack([np.array(SMPL_PARENTS, dtype=np.int64) % 4294967296, np.arange(24)])
    return {
        "v_template": v,
        "f": f.astype(np.uint32),
        "J_regressor": jreg,
        "weights": w,
        "posedirs": 1e-3 * rng.standard_normal((n_verts, 3, 207)),
        "shapedirs": 1e-2 * rng.standard_normal((n_verts, 3, 10)),
        "kintree_table": kintree,
    }


@pytest.fixture(scope="session")
def smpl_arrays():
    """The :func:`make_smpl_arrays` builder (a fixture, so tests need not import conftest)."""
    return make_smpl_arrays


@pytest.fixture(scope="session")
def smpl_file(tmp_path_factory) -> Path:
    """A synthetic SMPL-format ``.npz`` (6890 vertices, 24 joints, no UVs)."""
    path = tmp_path_factory.mktemp("smpl") / "synthetic_smpl.npz"
    np.savez(path, **make_smpl_arrays())
    return path
