import math

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.sh import fibonacci_sphere, sh_basis, sh_count, sh_index
from relightnet.sh.basis import SHBasis


def _rand_dirs(n, dtype=torch.float64, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.nn.functional.normalize(torch.randn(n, 3, generator=g, dtype=dtype), dim=-1)


def test_order2_constants_literal():
    d = _rand_dirs(50)
    x, y, z = d.unbind(-1)
    expected = torch.stack(
        [
            torch.full_like(x, 0.282095),
            0.488603 * y,
            0.488603 * z,
            0.488603 * x,
            1.092548 * x * y,
            1.092548 * y * z,
            0.315392 * (3 * z * z - 1),
            1.092548 * x * z,
            0.546274 * (x * x - y * y),
        ],
        -1,
    )
    torch.testing.assert_close(sh_basis(d, 2), expected, atol=2e-6, rtol=0)


@pytest.mark.parametrize("lmax", [0, 1, 2, 3, 4])
def test_orthonormal_by_quadrature(lmax):
    d, w = fibonacci_sphere(40000, torch.float64)
    Y = sh_basis(d, lmax)
    G = (Y * w[:, None]).T @ Y
    assert (G - torch.eye(sh_count(lmax), dtype=G.dtype)).abs().max() <= 1e-4


def test_matches_spherical_form_order3():
    # Y_3^{-3}, Y_3^0, Y_3^3 of the textbook closed forms (no Condon-Shortley phase).
    d = _rand_dirs(20)
    x, y, z = d.unbind(-1)
    Y = sh_basis(d, 3)
    c33 = 0.25 * math.sqrt(35 / (2 * math.pi))
    torch.testing.assert_close(Y[:, sh_index(3, -3)], c33 * y * (3 * x * x - y * y))
    torch.testing.assert_close(Y[:, sh_index(3, 3)], c33 * x * (x * x - 3 * y * y))
    torch.testing.assert_close(Y[:, sh_index(3, 0)], 0.25 * math.sqrt(7 / math.pi) * z * (5 * z * z - 3))


def test_batched_shapes_dtypes_and_grad():
    d = _rand_dirs(24, torch.float32).reshape(2, 3, 4, 3)
    out = SHBasis(4)(d)
    assert out.shape == (2, 3, 4, 25) and out.dtype == torch.float32
    d64 = _rand_dirs(5).requires_grad_(True)
    sh_basis(d64, 3).sum().backward()
    assert torch.isfinite(d64.grad).all()


def test_poles_are_exact():
    Y = sh_basis(torch.tensor([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]], dtype=torch.float64), 4)
    m_nonzero = [k for k in range(25) if k not in (0, 2, 6, 12, 20)]
    assert Y[:, m_nonzero].abs().max() == 0


def test_bad_inputs():
    with pytest.raises(ShapeError, match=r"dirs: expected \(\.\.\., 3\), got \(4, 2\)"):
        sh_basis(torch.ones(4, 2), 2)
    with pytest.raises(InputError, match="unit vectors"):
        sh_basis(torch.ones(4, 3), 2)
    with pytest.raises(InputError, match="NaN"):
        sh_basis(torch.full((2, 3), float("nan")), 2)
    with pytest.raises(ValueError, match="lmax"):
        sh_basis(_rand_dirs(3), -1)


def test_high_orders_stay_finite_in_float32():
    # (2m-1)!! leaves float32's range at m = 29; high orders are evaluated in float64.
    d = torch.nn.functional.normalize(torch.randn(500, 3, generator=torch.Generator().manual_seed(0)), dim=-1)
    for lmax in (28, 30, 40):
        b = sh_basis(d, lmax)
        assert b.dtype == torch.float32 and torch.isfinite(b).all()
        torch.testing.assert_close(b.double(), sh_basis(d.double(), lmax), rtol=0, atol=1e-5)


def test_basis_on_device_matches_float64_cpu(device, dtype):
    d = _rand_dirs(300)
    out = sh_basis(d.to(device, dtype), 4)
    assert out.device.type == device.type and out.dtype == dtype and out.shape == (300, 25)
    tol = 2e-6 if dtype == torch.float32 else 1e-12
    torch.testing.assert_close(out.cpu().double(), sh_basis(d, 4), atol=tol, rtol=0)


def test_basis_gradcheck(device):
    d = _rand_dirs(5).to(device).requires_grad_(True)
    # the basis takes unit vectors: normalise inside so gradcheck's perturbed inputs stay valid
    assert torch.autograd.gradcheck(lambda x: sh_basis(torch.nn.functional.normalize(x, dim=-1), 3), (d,))
