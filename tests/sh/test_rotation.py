import math

import pytest
import torch

from relightnet.sh import rotate_sh, rotate_sh_up, sh_basis
from relightnet.sh.rotation import RotateSH, rotation_about_up, sh_rotation_matrix


def _rot(seed, n=None):
    g = torch.Generator().manual_seed(seed)
    A = torch.randn(*(() if n is None else (n,)), 3, 3, generator=g, dtype=torch.float64)
    Q, _ = torch.linalg.qr(A)
    return Q * torch.sign(torch.linalg.det(Q))[..., None, None]


def _dirs(n, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.nn.functional.normalize(torch.randn(n, 3, generator=g, dtype=torch.float64), dim=-1)


@pytest.mark.parametrize("lmax", [1, 2, 3, 4])
def test_equivariance(lmax):
    R = _rot(lmax)
    c = torch.randn((lmax + 1) ** 2, 3, dtype=torch.float64)
    d = _dirs(300)
    # f'(w) = f(R^T w): evaluate rotated coefficients at d == original at R^T d.
    lhs = sh_basis(d, lmax) @ rotate_sh(c, R)
    rhs = sh_basis(d @ R, lmax) @ c
    assert (lhs - rhs).abs().max() <= 1e-5


def test_composition_and_inverse():
    R1, R2 = _rot(10), _rot(11)
    M = sh_rotation_matrix(torch.stack([R1, R2, R2 @ R1]), 4)
    torch.testing.assert_close(M[1] @ M[0], M[2], atol=1e-10, rtol=0)
    Mi = sh_rotation_matrix(R1.T, 4)
    torch.testing.assert_close(Mi @ M[0], torch.eye(25, dtype=torch.float64), atol=1e-10, rtol=0)
    # Orthogonal and block diagonal.
    torch.testing.assert_close(M[0] @ M[0].T, torch.eye(25, dtype=torch.float64), atol=1e-10, rtol=0)
    assert M[0][0, 1:].abs().max() == 0 and M[0][1:4, 4:].abs().max() == 0


def test_batched_rotation_of_many_lights():
    R = _rot(3, 4)
    c = torch.randn(4, 9, 3, dtype=torch.float64)
    out = rotate_sh(c, R)
    torch.testing.assert_close(out[2], rotate_sh(c[2], R[2]))
    torch.testing.assert_close(RotateSH(R[1])(c[1]), out[1])


def test_rotation_about_up_moves_a_lobe():
    # A light along +x_light (toward camera), turned 90 deg about up, points along +y_light.
    x = torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64)
    y = torch.tensor([0.0, 1.0, 0.0], dtype=torch.float64)
    c = sh_basis(x, 2)[:, None].repeat(1, 3)
    turned = rotate_sh_up(c, math.pi / 2)
    torch.testing.assert_close(turned, sh_basis(y, 2)[:, None].repeat(1, 3), atol=1e-10, rtol=0)
    assert rotation_about_up(torch.zeros(5)).shape == (5, 3, 3)


def test_rejects_non_rotations():
    with pytest.raises(ValueError, match="proper rotation"):
        sh_rotation_matrix(torch.diag(torch.tensor([1.0, 1.0, -1.0])), 2)
    with pytest.raises(ValueError, match="proper rotation"):
        sh_rotation_matrix(2 * torch.eye(3), 2)
