"""Light distance = L2 of the irradiance difference over the sphere; outlier thresholds."""

import math

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.light import preset_light
from relightnet.sh import fibonacci_sphere, irradiance
from relightnet.temporal import light_distance
from relightnet.temporal.distance import light_norm, light_weights, outlier_threshold, parse_eps, robust_scale


@pytest.mark.parametrize("lmax", [1, 2, 3])
def test_distance_is_the_irradiance_integral_over_the_sphere(lmax):
    g = torch.Generator().manual_seed(lmax)
    k = (lmax + 1) ** 2
    a = torch.randn(k, 3, generator=g, dtype=torch.float64)
    b = torch.randn(k, 3, generator=g, dtype=torch.float64)
    dirs, w = fibonacci_sphere(40000, dtype=torch.float64)
    diff = irradiance(a, dirs) - irradiance(b, dirs)  # (N, 3)
    integral = (w[:, None] * diff.square()).sum()
    torch.testing.assert_close(light_distance(a, b, squared=True), integral, rtol=1e-4, atol=0)
    torch.testing.assert_close(light_distance(a, b), integral.sqrt(), rtol=1e-4, atol=0)


def test_weights_are_squared_cosine_lobes():
    w = light_weights(9, dtype=torch.float64)
    ref = torch.tensor([math.pi**2] + [(2 * math.pi / 3) ** 2] * 3 + [(math.pi / 4) ** 2] * 5, dtype=torch.float64)
    torch.testing.assert_close(w, ref)


def test_distance_properties_shapes_and_gradient():
    a = preset_light("studio")
    b = preset_light("sunset")
    assert light_distance(a, a).item() == 0
    torch.testing.assert_close(light_distance(a, b), light_distance(b, a))
    torch.testing.assert_close(light_norm(a), light_distance(a, torch.zeros_like(a)))
    # Triangle inequality (it is a norm of the difference).
    c = preset_light("night")
    assert light_distance(a, c) <= light_distance(a, b) + light_distance(b, c) + 1e-5
    seq = torch.stack([a, b, c])  # (3, 9, 3) broadcasts against (9, 3)
    d = light_distance(seq, a)
    assert d.shape == (3,) and d[0] == 0
    assert light_distance(torch.zeros(2, 5, 9, 3)).shape == (2, 5)
    x = a.clone().requires_grad_(True)
    light_distance(x, a).backward()  # gradient at exactly zero distance stays finite
    assert torch.isfinite(x.grad).all()
    with pytest.raises(ShapeError):
        light_distance(torch.zeros(8, 3))
    with pytest.raises(ShapeError):
        light_distance(torch.zeros(9, 2))


def test_parse_eps():
    assert parse_eps(None) is None and parse_eps("none") is None and parse_eps(" None ") is None
    assert parse_eps("3mad") == ("mad", 3.0)
    assert parse_eps("2.5 MAD") == ("mad", 2.5)
    assert parse_eps("0.25") == ("abs", 0.25)
    assert parse_eps(1) == ("abs", 1.0)
    for bad in ["mad", "3sigma", "-1", "abc", "inf", "nan", "-2mad", True, [3]]:
        with pytest.raises(InputError):
            parse_eps(bad)


def test_outlier_threshold_robust_and_absolute():
    d = torch.tensor([[1.0, 2.0, 3.0, 4.0, 100.0]])
    med, sigma = robust_scale(d)
    assert med.item() == 3.0 and sigma.item() == pytest.approx(1.4826)  # MAD = median(2,1,0,1,97) = 1
    assert outlier_threshold(d, "3mad").item() == pytest.approx(3 + 3 * 1.4826)
    assert outlier_threshold(d, 7.5).item() == 7.5
    assert outlier_threshold(d, None).item() == math.inf
    # The floor protects exactly-fitted data (MAD = 0) from flagging rounding errors.
    z = torch.zeros(2, 6)
    torch.testing.assert_close(outlier_threshold(z, "3mad", floor=0.1), torch.full((2,), 0.1))
