"""Light metrics: scale invariance, the ambient baseline, directions and colour."""

import math

import pytest
import torch

from relightnet.light import ambient_light, directional_light
from relightnet.sh.metrics import (
    chromaticity_error,
    direction_error,
    dominant_direction,
    irradiance_samples,
    scale_invariant_light_error,
)


def test_error_is_scale_invariant_but_not_colour_invariant():
    L = directional_light([0.3, 0.5, 0.8], [1.0, 0.8, 0.6], sharpness=8.0) + ambient_light(0.1)
    assert float(scale_invariant_light_error(L, L)) < 1e-5
    assert float(scale_invariant_light_error(3.7 * L, L)) < 1e-5
    tinted = L * torch.tensor([1.0, 1.0, 0.5])
    assert float(scale_invariant_light_error(tinted, L)) > 0.05


def test_zero_and_ambient_estimates():
    L = directional_light([0.0, 1.0, 0.0], 1.0, sharpness=4.0) + ambient_light(0.05)
    assert float(scale_invariant_light_error(torch.zeros_like(L), L)) == pytest.approx(1.0)
    amb = torch.zeros_like(L)
    amb[0] = L[0]
    assert 0.2 < float(scale_invariant_light_error(amb, L)) < 1.0
    # the exact sphere error equals the sampled one (orthonormal SH)
    a, b = irradiance_samples(amb), irradiance_samples(L)
    sampled = (1 - (a * b).sum() ** 2 / ((a * a).sum() * (b * b).sum())).sqrt()
    assert float(scale_invariant_light_error(amb, L)) == pytest.approx(float(sampled), abs=2e-3)


def test_hemisphere_looks_at_the_camera_side_only():
    front = directional_light([1.0, 0.0, 0.0], 1.0, sharpness=6.0) + ambient_light(0.02)
    back = directional_light([-1.0, 0.0, 0.0], 1.0, sharpness=6.0) + ambient_light(0.02)
    d = irradiance_samples(front, hemisphere=True)
    assert d.shape[0] < 4096 // 2 + 50
    est = front + 0.2 * back
    err = scale_invariant_light_error
    assert float(err(est, front, hemisphere=True)) < float(err(est, front))


def test_dominant_direction_and_angle():
    for d in ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -0.6, 0.8]):
        L = directional_light(d, 1.0, sharpness=5.0)
        assert torch.allclose(dominant_direction(L), torch.tensor(d, dtype=torch.float64), atol=1e-5)
    a = directional_light([1.0, 0.0, 0.0], 1.0)
    b = directional_light([math.cos(0.5), math.sin(0.5), 0.0], 1.0)
    assert float(direction_error(a, b)) == pytest.approx(math.degrees(0.5), abs=1e-3)


def test_chromaticity():
    L = ambient_light([0.5, 0.5, 0.5])
    assert float(chromaticity_error(L, 2 * L)) < 1e-9
    assert float(chromaticity_error(ambient_light([0.6, 0.5, 0.4]), L)) > 0.05
