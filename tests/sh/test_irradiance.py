import math

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.sh import cosine_lobe, fibonacci_sphere, irradiance, sh_basis
from relightnet.sh.irradiance import Irradiance


def _dirs(n, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.nn.functional.normalize(torch.randn(n, 3, generator=g, dtype=torch.float64), dim=-1)


def test_cosine_lobe_values():
    assert cosine_lobe(0) == pytest.approx(math.pi)
    assert cosine_lobe(1) == pytest.approx(2 * math.pi / 3)
    assert cosine_lobe(2) == pytest.approx(math.pi / 4)
    assert cosine_lobe(3) == 0 and cosine_lobe(5) == 0
    assert cosine_lobe(4) == pytest.approx(-math.pi / 24)
    assert cosine_lobe(6) == pytest.approx(math.pi / 64)


@pytest.mark.parametrize("l", [0, 1, 2, 3, 4, 6])
def test_cosine_lobe_by_quadrature(l):
    # Funk-Hecke: the zonal projection of max(cos, 0) is A_l * Y_l0(z-axis).
    d, w = fibonacci_sphere(200000, torch.float64)
    Y = sh_basis(d, l)[:, l * l + l]
    c = (w * Y * d[:, 2].clamp_min(0)).sum()
    y_pole = math.sqrt((2 * l + 1) / (4 * math.pi))
    assert c.item() == pytest.approx(cosine_lobe(l) * y_pole, abs=2e-4)


def test_constant_environment_gives_pi():
    L = torch.zeros(9, 3, dtype=torch.float64)
    L[0] = 1 / 0.28209479177387814  # radiance 1 everywhere
    E = irradiance(L, _dirs(100))
    torch.testing.assert_close(E, torch.full_like(E, math.pi))


def test_ramamoorthi_hanrahan_polynomial():
    c1, c2, c3, c4, c5 = 0.429043, 0.511664, 0.743125, 0.886227, 0.247708
    g = torch.Generator().manual_seed(3)
    L = torch.randn(9, 3, generator=g, dtype=torch.float64)
    n = _dirs(200, 1)
    x, y, z = (t[:, None] for t in n.unbind(-1))
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = L
    E = (
        c1 * L22 * (x * x - y * y) + c3 * L20 * z * z + c4 * L00 - c5 * L20
        + 2 * c1 * (L2m2 * x * y + L21 * x * z + L2m1 * y * z)
        + 2 * c2 * (L11 * x + L1m1 * y + L10 * z)
    )
    torch.testing.assert_close(irradiance(L, n), E, atol=1e-5, rtol=0)


def test_matches_numerical_cosine_integral():
    d, w = fibonacci_sphere(100000, torch.float64)
    g = torch.Generator().manual_seed(5)
    L = torch.randn(16, 3, generator=g, dtype=torch.float64)
    rad = sh_basis(d, 3) @ L
    n = _dirs(8, 2)
    E_num = ((n @ d.T).clamp_min(0) * w) @ rad
    torch.testing.assert_close(irradiance(L, n), E_num, atol=2e-3, rtol=0)


def test_batched_light_and_module():
    L = torch.randn(2, 9, 3, dtype=torch.float64)
    n = _dirs(10).reshape(2, 5, 3)
    E = irradiance(L, n)
    torch.testing.assert_close(E[1], irradiance(L[1], n[1]))
    torch.testing.assert_close(Irradiance(L[0])(n[0]), E[0])


def test_bad_inputs():
    with pytest.raises(ShapeError, match="sh: expected K"):
        irradiance(torch.zeros(8, 3), _dirs(2))
    with pytest.raises(InputError, match="sh: contains NaN"):
        irradiance(torch.full((9, 3), float("nan")), _dirs(2))
    with pytest.raises(ShapeError, match=r"sh: expected \(\.\.\., K, 3\)"):
        irradiance(torch.zeros(9, 4), _dirs(2))


def test_irradiance_on_device_matches_float64_cpu(device, dtype):
    n = _dirs(200)
    L = torch.randn(2, 9, 3, generator=torch.Generator().manual_seed(1), dtype=torch.float64)
    ref = irradiance(L, n.expand(2, -1, -1))
    out = irradiance(L.to(device, dtype), n.expand(2, -1, -1).to(device, dtype))
    assert out.device.type == device.type and out.dtype == dtype and out.shape == (2, 200, 3)
    tol = 1e-5 if dtype == torch.float32 else 1e-12
    torch.testing.assert_close(out.cpu().double(), ref, atol=tol, rtol=tol)


def test_irradiance_gradcheck(device):
    n = _dirs(6).to(device).requires_grad_(True)
    L = torch.randn(9, 3, generator=torch.Generator().manual_seed(2), dtype=torch.float64).to(device)
    L.requires_grad_(True)
    f = lambda light, normals: irradiance(light, torch.nn.functional.normalize(normals, dim=-1))  # noqa: E731
    assert torch.autograd.gradcheck(f, (L, n))


# The cone transport: the clamped cosine seen through a cone of visibility (closed form).

def test_cone_band_factors_open_and_closed():
    from relightnet.sh.irradiance import cone_band_factors

    g = cone_band_factors(torch.tensor([0.0, 1.0], dtype=torch.float64), 6)
    torch.testing.assert_close(g[0], torch.tensor([cosine_lobe(l) for l in range(7)], dtype=torch.float64))
    torch.testing.assert_close(g[1], torch.zeros(7, dtype=torch.float64))


@pytest.mark.parametrize("c", [0.0, 0.3, 0.6, 0.9])
def test_cone_transport_by_quadrature(c):
    # A spherical Fibonacci lattice of 200,000 points integrates the cone's discontinuous indicator
    # with an error of the order of the rim's share of the points, ~ 1/sqrt(N) ≈ 2e-3 of the lobe.
    from relightnet.sh import cone_transport

    d, w = fibonacci_sphere(200000, torch.float64)
    axes = _dirs(3, seed=4)
    for b in axes:
        t = d @ b
        f = torch.where(t >= c, t, torch.zeros_like(t))
        numeric = (f[:, None] * sh_basis(d, 3) * w[:, None]).sum(0)
        closed = cone_transport(b, torch.tensor(c, dtype=torch.float64), 3)
        torch.testing.assert_close(closed, numeric, atol=3e-3, rtol=0)


def test_cone_transport_open_cone_is_unoccluded_transport():
    from relightnet.sh import cone_transport
    from relightnet.sh.irradiance import cosine_lobe_per_coeff

    n = _dirs(50)
    T = cone_transport(n, torch.zeros(50, dtype=torch.float64), 2)
    torch.testing.assert_close(T, sh_basis(n, 2) * cosine_lobe_per_coeff(2, dtype=torch.float64))


def test_cone_transport_shapes_and_gradients():
    from relightnet.sh import cone_transport

    axis = _dirs(12).view(3, 4, 3).requires_grad_()
    c = torch.rand(3, 4, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda a, cc: cone_transport(a, cc, 2, check=False), (axis, c))
    with pytest.raises(ShapeError):
        cone_transport(axis, c[:, :3], 2)
