"""The light of a background plate: the frustum lands where the camera looked, the fill rule, units,
the person/plate combination, files."""

import math

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from relightnet.checks import InputError
from relightnet.data.backgrounds import envmap_background
from relightnet.io import write_image
from relightnet.sh import (
    ambient_light,
    combine_person_plate,
    dominant_direction,
    latlong_directions,
    light_from_words,
    load_plate_light,
    plate_envmap,
    plate_light,
    preset_envmap,
    radiance,
)


def _plate(env, hfov=60.0, res=128):
    f = 0.5 * res / math.tan(math.radians(hfov) / 2)
    return envmap_background(env, (f, f, res / 2, res / 2), res, torch.eye(3, dtype=torch.float64), 1.0)


def test_the_frustum_lands_where_the_camera_looked():
    env = preset_envmap("sunset")
    h = 64
    small = F.interpolate(env.permute(2, 0, 1)[None], size=(h, 2 * h), mode="area")[0].permute(1, 2, 0)
    got = plate_envmap(_plate(env, res=256), 60.0, h=h, work=256) * math.pi
    d, _ = latlong_directions(h, 2 * h, dtype=torch.float64)
    x, y, z = d.unbind(-1)
    inside = (z < 0) & ((x / -z).abs() < 0.5) & ((y / -z).abs() < 0.5)
    rel = float((got[inside] - small[inside]).abs().mean() / small[inside].abs().mean())
    flipped = float((got.flip(1)[inside] - small[inside]).abs().mean() / small[inside].abs().mean())
    assert rel < 0.05 and flipped > 4 * rel  # resampling error only, and the orientation matters


def test_fill_rule_sky_ground_and_mirror():
    # A plate bright at the top and dark at the bottom: light from above, none from the front/back axis.
    plate = torch.zeros(64, 96, 3)
    plate[:32] = 1.0
    plate[32:] = 0.1
    env = plate_envmap(plate, 60.0, h=32)
    assert float(env[0].mean()) > 5 * float(env[-1].mean())  # sky above, ground below
    # behind the camera mirrors the front: columns at ±90° from the view axis are symmetric
    d, _ = latlong_directions(32, 64, dtype=torch.float64)
    front, back = d[..., 2] < 0, d[..., 2] > 0
    assert abs(float(env[front].mean()) - float(env[back].mean())) < 1e-3 * float(env.mean())
    sh = plate_light(plate, 2)
    up = dominant_direction(sh)
    assert float(up[2]) > 0.9 and abs(float(sh[3, 0])) < 1e-4 * float(sh[0, 0])  # no front/back term


def test_units_a_uniform_plate_is_an_ambient_light():
    """A white person under a uniform plate of linear value p shows p: radiance p / π everywhere."""
    p = 0.4
    sh = plate_light(torch.full((48, 64, 3), p), 2)
    want = ambient_light(p / math.pi)
    # the lat-long quadrature of a constant is exact up to O(1/H²) in the higher bands
    torch.testing.assert_close(sh, want, rtol=1e-4, atol=1e-3 * float(want[0, 0]))


def test_intrinsics_override_the_field_of_view():
    env = preset_envmap("city")
    plate = _plate(env, hfov=40.0)
    f = 0.5 * 128 / math.tan(math.radians(20))
    a = plate_light(plate, 2, 40.0)
    b = plate_light(plate, 2, intrinsics=(f, f, 64, 64))
    torch.testing.assert_close(a, b, rtol=1e-5, atol=1e-6)
    assert float((plate_light(plate, 2, 90.0) - a).abs().max()) > 1e-4


def test_bad_inputs_are_named(tmp_path):
    with pytest.raises(InputError, match="plate field of view"):
        plate_light(torch.ones(8, 8, 3), 2, 180.0)
    with pytest.raises(InputError, match="no such file"):
        load_plate_light(tmp_path / "nope.jpg")
    with pytest.raises(InputError, match="NaN"):
        plate_light(torch.full((8, 8, 3), float("nan")), 2)


def test_load_plate_light_linearises_the_photo(tmp_path):
    img = np.full((40, 60, 3), 128, np.uint8)
    write_image(tmp_path / "p.png", img)
    sh = load_plate_light(tmp_path / "p.png")
    p = ((128 / 255 + 0.055) / 1.055) ** 2.4  # inverse sRGB, exposure kept
    want = ambient_light(p / math.pi)
    torch.testing.assert_close(sh, want, rtol=1e-4, atol=1e-3 * float(want[0, 0]))


def test_combination_takes_each_light_where_it_sees():
    person = light_from_words("key:az=0,el=0,size=60,power=2")  # from the camera
    plate = light_from_words("key:az=180,el=0,size=60,power=2")  # from behind the person
    both = combine_person_plate(person, plate)
    front = torch.tensor([[1.0, 0.0, 0.0]])
    back = -front
    torch.testing.assert_close(radiance(both, front), radiance(person, front), rtol=0.15, atol=0.02)
    torch.testing.assert_close(radiance(both, back), radiance(plate, back), rtol=0.15, atol=0.02)
    seq = combine_person_plate(torch.stack([person, person]), plate)  # a sequence of person lights
    torch.testing.assert_close(seq[1], both)
    same = combine_person_plate(person, person)  # agreeing lights are kept
    torch.testing.assert_close(same, person, rtol=1e-4, atol=1e-5)
