import math

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.sh import (
    fibonacci_sphere,
    project,
    project_envmap,
    radiance,
    sh_basis,
    sh_to_envmap,
)


def test_project_band_limited_function_reproduces_coefficients():
    d, w = fibonacci_sphere(20000, torch.float64)
    c = torch.randn(16, 3, dtype=torch.float64)
    Y = sh_basis(d, 3)
    torch.testing.assert_close(project(Y @ c, Y, w), c, atol=1e-4, rtol=0)


def test_envmap_round_trip_known_coefficients():
    g = torch.Generator().manual_seed(0)
    c = torch.randn(9, 3, generator=g, dtype=torch.float64)
    c[0] += 10  # keep radiance positive so clamping does not bite
    env = sh_to_envmap(c, 256, 512)
    assert env.min() > 0
    torch.testing.assert_close(project_envmap(env, 2), c, atol=2e-4, rtol=0)


def test_envmap_constant_and_sun_direction():
    env = torch.ones(256, 512, 3)  # midpoint rule in theta: error O(1/H^2)
    c = project_envmap(env, 2)
    assert c[0, 0].item() == pytest.approx(math.sqrt(4 * math.pi), rel=1e-4)
    assert c[1:].abs().max() < 1e-4
    # A bright spot at the top row is "up": positive z_light (k=2) coefficient.
    env = torch.zeros(64, 128, 3)
    env[0] = 100
    assert project_envmap(env, 1)[2, 0] > 0
    # The image centre looks along -z_world, i.e. -x_light (away from the camera).
    env = torch.zeros(64, 128, 3)
    env[30:34, 62:66] = 100
    c = project_envmap(env, 1)
    assert c[3, 0] < 0 and abs(c[3, 0]) > 10 * abs(c[1, 0])


def test_envmap_clamps_negative_and_rejects_bad():
    env = torch.ones(32, 64, 3)
    env[0, 0] = -5
    torch.testing.assert_close(project_envmap(env, 0), project_envmap(env.clamp_min(0), 0))
    with pytest.raises(ShapeError, match="env: expected"):
        project_envmap(torch.ones(32, 64), 2)
    with pytest.raises(InputError, match="env: contains NaN"):
        project_envmap(torch.full((8, 16, 3), float("nan")), 2)


def test_radiance_consistent_with_basis():
    c = torch.randn(9, 3, dtype=torch.float64)
    d = torch.nn.functional.normalize(torch.randn(10, 3, dtype=torch.float64), dim=-1)
    torch.testing.assert_close(radiance(c, d), sh_basis(d, 2) @ c)
    env = sh_to_envmap(c, 8)
    assert env.shape == (8, 16, 3)
