"""Preset environment-map lights and analytic lights."""

import math

import pytest
import torch

from relightnet.checks import InputError
from relightnet.light import ambient_light, directional_light, preset_light, preset_names
from relightnet.sh import fibonacci_sphere, irradiance, project, radiance, rotate_sh, sh_basis

EIGHT = ["city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset"]


def test_the_eight_presets_load():
    assert preset_names() == EIGHT
    for name in EIGHT:
        sh = preset_light(name)
        assert sh.shape == (9, 3) and sh.dtype == torch.float32
        assert torch.isfinite(sh).all()
        assert (sh[0] > 0).all(), name


def test_preset_orders_are_nested_and_cache_hands_out_copies():
    sh2, sh3 = preset_light("sunset", 2), preset_light("sunset", 3)
    assert sh3.shape == (16, 3)
    torch.testing.assert_close(sh3[:9], sh2)
    sh2[0] = -1  # mutating a result must not poison the cache
    assert (preset_light("sunset", 2)[0] > 0).all()


def test_sunset_light_comes_from_near_the_horizon_behind_right():
    # The sun (an orange-red peak) is slightly above the horizon, behind the subject (-z_world,
    # i.e. -x_light) and to the right (+x_world, +y_light): the red order-1 direction points there.
    sh = preset_light("sunset")
    y, z, x = sh[1:4, 0]  # order-1 coefficients ∝ (y, z, x) light-frame components
    assert x < 0 and y > 0 and abs(z) < max(abs(x), abs(y))


def test_unknown_preset_lists_names():
    with pytest.raises(InputError) as e:
        preset_light("sunny")
    assert "sunny" in str(e.value) and all(n in str(e.value) for n in EIGHT)


def test_ambient_is_constant_radiance():
    sh = ambient_light([0.5, 1.0, 2.0], lmax=3)
    assert sh.shape == (16, 3) and (sh[1:] == 0).all()
    d, _ = fibonacci_sphere(100)
    torch.testing.assert_close(radiance(sh, d), torch.tensor([0.5, 1.0, 2.0]).expand(100, 3))
    torch.testing.assert_close(irradiance(sh, d), math.pi * torch.tensor([0.5, 1.0, 2.0]).expand(100, 3))
    torch.testing.assert_close(ambient_light(2.0, 0), torch.full((1, 3), 2.0 * math.sqrt(4 * math.pi)))


def test_directional_is_band_limited_delta():
    d = torch.tensor([1.0, 2.0, 2.0]) / 3
    sh = directional_light(d * 7, color=[1.0, 0.5, 0.25], lmax=2)  # direction normalised
    torch.testing.assert_close(sh[:, 0], sh_basis(d, 2))
    torch.testing.assert_close(sh[:, 1], 0.5 * sh_basis(d, 2))
    # Irradiance toward the light ≈ color (order-2 clamped cosine: 1 + 1/16 at normal incidence).
    e = irradiance(sh, d[None])[0]
    torch.testing.assert_close(e, 1.0625 * torch.tensor([1.0, 0.5, 0.25]))
    # Radiance peaks toward the light.
    dirs, _ = fibonacci_sphere(2000)
    assert (dirs[radiance(sh, dirs)[:, 0].argmax()] @ d) > 0.99


def test_directional_rotates_with_its_direction():
    d = torch.tensor([0.0, 0.6, 0.8])
    a = 0.7
    R = torch.tensor([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1.0]])
    torch.testing.assert_close(
        rotate_sh(directional_light(d, 1.0, 3), R), directional_light(R @ d, 1.0, 3), rtol=0, atol=1e-5
    )


def test_directional_vmf_matches_numerical_projection():
    d = torch.tensor([0.0, 0.0, 1.0], dtype=torch.float64)
    kappa = 6.0
    dirs, w = fibonacci_sphere(40000, dtype=torch.float64)
    f = kappa / (4 * math.pi * math.sinh(kappa)) * torch.exp(kappa * (dirs @ d))  # integrates to 1
    ref = project(f[:, None], sh_basis(dirs, 4), w)[:, 0]
    sh = directional_light(d, 1.0, lmax=4, sharpness=kappa)
    torch.testing.assert_close(sh[:, 0].double(), ref, rtol=0, atol=1e-4)
    # A very sharp lobe tends to the delta.
    torch.testing.assert_close(directional_light(d, 1.0, 2, 1e5), directional_light(d, 1.0, 2), atol=1e-4, rtol=0)


def test_analytic_errors():
    with pytest.raises(InputError, match="direction"):
        directional_light([0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="direction"):
        directional_light([1.0, 0.0])
    with pytest.raises(InputError, match="sharpness"):
        directional_light([1.0, 0.0, 0.0], sharpness=-1.0)
    with pytest.raises(InputError, match="color"):
        ambient_light([1.0, 2.0])
    with pytest.raises(InputError, match="color"):
        ambient_light(float("nan"))


def test_side_light_is_power_times_the_basis_plus_ambient():
    from relightnet.light import side_light
    from relightnet.sh import sh_basis

    d = torch.tensor((0.5, -0.85, 0.2), dtype=torch.float64)
    expected = 3 * sh_basis(d / d.norm(), 2)[:, None].expand(9, 3).clone()
    expected[0] += 0.3
    torch.testing.assert_close(side_light((0.5, -0.85, 0.2)), expected.float())
    torch.testing.assert_close(side_light(d, 2.0, 0.1, lmax=1)[0], torch.full((3,), 2 * 0.28209479 + 0.1))
