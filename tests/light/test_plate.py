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
from relightnet.light import (
    ambient_light,
    combine_person_plate,
    light_from_words,
    plate_envmap,
    plate_light,
    plate_seen,
    preset_envmap,
)
from relightnet.light.plate import SEEN_FADE_DEG, PlateView, load_plate_light, plate_view
from relightnet.sh import (
    dominant_direction,
    fibonacci_sphere,
    latlong_directions,
    project,
    radiance,
    sh_basis,
    world_to_light,
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


def test_plate_seen_is_its_frame_with_a_soft_edge():
    view = plate_view(90, 160, 60.0)  # a centred 60° × ~36° pinhole
    assert view == PlateView(view.fx, view.fx, 80.0, 45.0, 160, 90)
    half_w, half_h = math.radians(30.0), math.atan(45.0 / view.fy)
    fade = math.radians(SEEN_FADE_DEG)

    def toward(az, el):  # world: right of the view axis by az, above it by el (tangent angles)
        v = torch.tensor([[math.tan(az), math.tan(el), -1.0]], dtype=torch.float64)
        return world_to_light(v / v.norm())

    assert float(plate_seen(toward(0, 0), view)) == 1.0
    assert float(plate_seen(toward(half_w - 1e-3, half_h - 1e-3), view)) == 1.0  # the frame's corner
    torch.testing.assert_close(plate_seen(toward(half_w + fade / 2, 0), view).item(), 0.5, rtol=0, atol=1e-9)
    torch.testing.assert_close(plate_seen(toward(0, -half_h - fade / 4), view).item(), 0.75, rtol=0, atol=1e-9)
    assert float(plate_seen(toward(half_w + fade, 0), view)) == 0.0
    assert float(plate_seen(-toward(0, 0), view)) == 0.0  # behind the camera
    with pytest.raises(InputError, match="field of view"):
        plate_view(90, 160, 170.0)
    with pytest.raises(InputError, match="fade_deg"):
        plate_seen(toward(0, 0), view, 0.0)


def test_combination_takes_the_plate_where_it_was_seen():
    view = plate_view(128, 128, 60.0)
    person = light_from_words("key:az=0,el=0,size=60,power=2")  # from the camera
    plate = light_from_words("key:az=180,el=0,size=60,power=2")  # from behind the person
    seen = plate_seen(fibonacci_sphere(4096, dtype=torch.float64)[0], view)
    expect = combine_person_plate(person, plate, view)
    # the blend is a linear map: two lights that agree are kept whatever the weights
    torch.testing.assert_close(combine_person_plate(person, person, view), person, rtol=1e-4, atol=1e-5)
    # the same blend integrated on another quadrature (a 256 × 512 lat-long grid, no clamping): the
    # weight's kinks at the frame's soft edge limit both quadratures to ~1e-4 of the light's scale
    dw, sa = latlong_directions(256, 512, dtype=torch.float64)
    dl = world_to_light(dw.reshape(-1, 3))
    w = plate_seen(dl, view)[:, None]
    vals = (1 - w) * radiance(person.double(), dl) + w * radiance(plate.double(), dl)
    ref = project(vals, sh_basis(dl, 2), sa.reshape(-1))
    torch.testing.assert_close(expect.double(), ref, rtol=0, atol=1e-3 * float(ref.abs().max()))
    back = torch.tensor([[-1.0, 0.0, 0.0]])  # where the plate looks: its light counts there
    assert float(radiance(expect, back).mean()) > float(radiance(person, back).mean())
    # the plate's share of the sphere: what its frame covers (about 1/15 of it at 60° × 60°)
    assert 0.04 < float(seen.mean()) < 0.12
    seq = combine_person_plate(torch.stack([person, person]), plate, view)  # a sequence of person lights
    torch.testing.assert_close(seq[1], expect)
    wide = combine_person_plate(person, plate, plate_view(128, 128, 150.0))
    assert float(radiance(wide, back).mean()) > float(radiance(expect, back).mean())  # a wider plate counts more
