"""The app's light controls: the sphere ⇄ direction, the sliders in words, the sources."""

import math

import pytest
import torch

from relightnet.app.controls import (
    direction_to_sphere_point,
    hex_to_rgb,
    light_of,
    sphere_point_to_direction,
    sphere_preview,
    words_of,
)
from relightnet.checks import InputError
from relightnet.light import light_from_words, preset_light


def test_sphere_points_and_directions_round_trip():
    for az, el in [(-40, 30), (0, 0), (75, -60), (-89, 5)]:
        x, y = direction_to_sphere_point(az, el, 200)
        a, e = sphere_point_to_direction(x, y, 200)
        assert abs(a - az) < 1e-6 and abs(e - el) < 1e-6
    assert sphere_point_to_direction(0, 100, 200) == pytest.approx((-90.0, 0.0))  # the left rim
    assert sphere_point_to_direction(100, 100, 200) == pytest.approx((0.0, 0.0))  # the centre: from the camera
    assert sphere_point_to_direction(100, -50, 200)[1] == pytest.approx(90.0)  # beyond the top: the rim
    assert direction_to_sphere_point(180, 0, 200) is None  # behind the person


def test_words_of_the_sliders_load():
    words = words_of(-40, 30, 20, 3, "#ffffff", 0.2)
    assert words == "key:az=-40,el=30,size=20,color=1/1/1,power=3 + ambient:0.2"
    torch.testing.assert_close(light_of("direction", words, None, None, None), light_from_words(words))
    assert "ambient" not in words_of(0, 0, 0, 1, "#ff0000", 0)
    assert hex_to_rgb("#ff0000") == (1.0, 0.0, 0.0)
    assert hex_to_rgb("rgba(255, 255, 255, 1)") == (1.0, 1.0, 1.0)
    assert hex_to_rgb("#808080")[0] == pytest.approx(((128 / 255 + 0.055) / 1.055) ** 2.4, abs=1e-4)


def test_sources():
    torch.testing.assert_close(light_of("preset", "", "sunset", None, None), preset_light("sunset"))
    with pytest.raises(InputError, match="HDRI file"):
        light_of("HDRI file", "", None, None, None)
    with pytest.raises(InputError, match="plate"):
        light_of("plate", "", None, None, None)
    with pytest.raises(InputError, match="light term 1"):
        light_of("direction", "key:az=x", None, None, None)


def test_sphere_preview_is_lit_on_the_lights_side():
    img = sphere_preview(light_from_words("key:az=-60,el=0,size=20"), 96, -60, 0)
    assert img.shape == (96, 96, 3) and img.dtype.name == "uint8"
    left, right = img[40:56, 8:30].mean(), img[40:56, 66:88].mean()
    assert left > right + 30
    x, y = direction_to_sphere_point(-60, 0, 96)
    assert tuple(img[int(round(y)), int(round(x))]) == (255, 60, 30)  # the marker
    assert math.isfinite(float(img.mean()))
