import json
import math

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.data.lights import (
    LEVEL_RANGE,
    LIGHT_SOURCES,
    lift_irradiance,
    light_at,
    light_level,
    luminance,
    mirror_sh,
    sample_light,
    synthetic_light,
    white_balance,
)
from relightnet.light import directional_light, preset_light
from relightnet.sh import fibonacci_sphere, irradiance, radiance, rotate_sh_up
from relightnet.sh.rotation import rotation_about_up


def _normals(n=2048):
    return fibonacci_sphere(n, dtype=torch.float64)[0]


def test_sample_light_uses_only_the_given_maps_and_respects_the_synthetic_probability():
    rng = np.random.default_rng(0)
    names = [sample_light(rng, ("night", "sunrise"), synthetic_prob=0.0) for _ in range(12)]
    assert {d.source for d in names} == {"hdri"}
    assert {d.hdri for d in names} <= {"night", "sunrise"} and len({d.hdri for d in names}) == 2
    synth = [sample_light(rng, ("night",), synthetic_prob=1.0) for _ in range(12)]
    assert {d.source for d in synth} <= set(LIGHT_SOURCES[1:]) and all(d.hdri is None for d in synth)
    assert len({d.source for d in synth}) >= 2
    with pytest.raises(InputError):
        sample_light(rng, ())


def test_sample_light_is_deterministic_and_json_describable():
    a = sample_light(np.random.default_rng(5), ("city", "forest"), synthetic_prob=0.5)
    b = sample_light(np.random.default_rng(5), ("city", "forest"), synthetic_prob=0.5)
    assert torch.equal(a.base, b.base) and a.angle == b.angle and a.info == b.info
    json.dumps(a.info)


@pytest.mark.parametrize("seed", range(6))
def test_light_is_normalised_to_its_level_and_lifted(seed):
    rng = np.random.default_rng(seed)
    d = sample_light(rng, ("city", "courtyard", "studio", "sunset"), synthetic_prob=0.5)
    assert LEVEL_RANGE[0] <= d.level <= LEVEL_RANGE[1]
    assert light_level(d.base) == pytest.approx(1.0, rel=1e-6)
    L = light_at(d)
    assert L.dtype == torch.float32 and L.shape == (9, 3)
    # The level is the max luminance of the irradiance; rotation and mirroring keep it
    # (up to the 256-normal sampling of the max, checked here on 2048 normals).
    E = luminance(irradiance(L.double(), _normals(), check=False))
    assert float(E.max()) == pytest.approx(d.level, rel=0.02)
    # Irradiance lift: every channel's irradiance stays above ~2 % of its maximum.
    Ec = irradiance(L.double(), _normals(), check=False)
    assert (Ec.amin(0) >= 0.015 * Ec.amax(0)).all()


def test_lift_adds_only_ambient_and_only_when_needed():
    sun = directional_light([0.3, 0.2, 0.9], [1.0, 0.9, 0.8])  # a band-limited delta rings below zero
    lifted, lift = lift_irradiance(sun)
    assert (lift > 0).all()
    assert torch.allclose(lifted[1:], sun[1:].double())  # only the DC term changes
    E = irradiance(lifted, _normals(), check=False)
    assert (E.amin(0) >= 0.02 * irradiance(sun.double(), _normals(256), check=False).amax(0) - 1e-3).all()
    amb = torch.zeros(9, 3)
    amb[0] = 1.0
    same, none = lift_irradiance(amb)
    assert torch.equal(none, torch.zeros(3, dtype=torch.float64)) and torch.equal(same, amb.double())


def test_mirror_flips_left_and_right():
    sh = preset_light("city")
    d = fibonacci_sphere(500)[0]
    flip = d * torch.tensor([1.0, -1.0, 1.0])
    assert torch.allclose(radiance(mirror_sh(sh), d), radiance(sh, flip), atol=1e-4)
    assert torch.allclose(mirror_sh(mirror_sh(sh)), sh)


def test_light_at_rotates_about_up_and_tilts():
    d = sample_light(np.random.default_rng(3), ("forest",), synthetic_prob=0.0)
    d = type(d)(d.base, d.source, d.hdri, d.angle, False, d.level, d.info)
    L0 = light_at(d, angle=0.0, level=1.0)
    assert torch.allclose(L0, d.base.float(), atol=1e-6)
    L1 = light_at(d, angle=0.7, level=2.0)
    assert torch.allclose(L1, 2.0 * rotate_sh_up(d.base, 0.7).float(), atol=1e-5)
    # A tilt about the up axis is just more rotation.
    L2 = light_at(d, angle=0.5, level=1.0, tilt=rotation_about_up(0.2, dtype=torch.float64))
    assert torch.allclose(L2, light_at(d, angle=0.7, level=1.0), atol=1e-5)


def test_white_balance_has_unit_luminance():
    rng = np.random.default_rng(1)
    for _ in range(20):
        g = white_balance(rng)
        assert (g > 0.6).all() and (g < 1.6).all()
        assert float(luminance(torch.as_tensor(g))) == pytest.approx(1.0)


@pytest.mark.parametrize("kind", ["sky_sun", "lobes", "fills"])
def test_synthetic_lights_are_plausible(kind):
    rng = np.random.default_rng(11)
    for _ in range(5):
        sh, params = synthetic_light(kind, rng)
        json.dumps(params)
        assert sh.shape == (9, 3) and torch.isfinite(sh).all()
        assert (sh[0] > 0).all()  # positive mean radiance in every channel
        E = luminance(irradiance(sh, _normals(256), check=False))
        assert float(E.max()) > 0
    if kind == "sky_sun":  # the sky (and the sun, above the horizon) light from above
        Eup = irradiance(sh, torch.tensor([[0.0, 0.0, 1.0]], dtype=torch.float64), check=False)
        Edown = irradiance(sh, torch.tensor([[0.0, 0.0, -1.0]], dtype=torch.float64), check=False)
        assert (Eup > Edown).all()
    with pytest.raises(InputError):
        synthetic_light("disco", rng)


def test_lobes_light_favours_the_camera_side():
    rng = np.random.default_rng(2)
    front = 0
    for _ in range(40):
        sh, params = synthetic_light("lobes", rng)
        front += math.cos(math.radians(params["lobes"][0]["azimuth_deg"])) > 0
    assert front >= 30  # key-light azimuth ~ N(0, 50°): 93 % of them within ±90° of the camera axis
