"""Lights in words: the grammar, the exact disc projection against a numerical one, errors."""

import math

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.cli import main
from relightnet.io import read_image
from relightnet.light import ambient_light, directional_light, light_from_words, load_light, words_envmap
from relightnet.light.words import camera_direction, disc_band_factors, disc_light, parse_light_words
from relightnet.sh import dominant_direction, irradiance, sh_basis

ISSUE = "key:az=-40,el=30,size=20,color=1.0/0.9/0.8,power=3 + fill:az=60,el=10,power=0.5 + ambient:0.2"


def _numerical_disc(d: torch.Tensor, size_deg: float, lmax: int, n_t: int = 64, n_phi: int = 128) -> torch.Tensor:
    """Project the unit-irradiance disc by quadrature over the cap: Gauss–Legendre in cos θ, uniform in φ."""
    alpha = math.radians(size_deg) / 2
    c = math.cos(alpha)
    x, w = np.polynomial.legendre.leggauss(n_t)
    t = torch.tensor(0.5 * (1 - c) * x + 0.5 * (1 + c), dtype=torch.float64)
    wt = torch.tensor(0.5 * (1 - c) * w, dtype=torch.float64)
    phi = torch.arange(n_phi, dtype=torch.float64) * (2 * math.pi / n_phi)
    s = (1 - t**2).clamp_min(0).sqrt()
    # An orthonormal frame (e1, e2, d) around the disc's axis.
    helper = torch.tensor([0.0, 0.0, 1.0], dtype=torch.float64)
    if abs(float(d @ helper)) > 0.9:
        helper = torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64)
    e1 = torch.linalg.cross(d, helper)
    e1 = e1 / e1.norm()
    e2 = torch.linalg.cross(d, e1)
    dirs = (s[:, None, None] * (torch.cos(phi)[None, :, None] * e1 + torch.sin(phi)[None, :, None] * e2)
            + t[:, None, None] * d)
    weights = wt[:, None] * (2 * math.pi / n_phi)
    omega = 2 * math.pi * (1 - c)
    return torch.einsum("tpk,tp->k", sh_basis(dirs, lmax, check=False), weights) / omega


@pytest.mark.parametrize("size", [1.0, 5.0, 20.0, 36.0, 37.0, 90.0, 179.0])
@pytest.mark.parametrize("az,el", [(-40.0, 30.0), (0.0, 0.0), (120.0, -75.0), (10.0, 89.0)])
def test_disc_matches_numerical_projection(size, az, el):
    d = camera_direction(az, el)
    exact = disc_light(d, size, 1.0, lmax=6)[:, 0]
    numeric = _numerical_disc(d, size, 6)
    # Both are float64; the quadrature is exact for polynomials of this degree, so 1e-4 is loose.
    torch.testing.assert_close(exact, numeric, rtol=0, atol=1e-4)


def test_band_factor_limits():
    torch.testing.assert_close(disc_band_factors(0.0, 4), torch.ones(5, dtype=torch.float64))
    full = disc_band_factors(180.0, 4)
    # A disc of diameter 180° is a hemisphere: P_l's mean over [0, 1] vanishes for even l > 0.
    assert abs(float(full[0]) - 1) < 1e-12 and abs(float(full[2])) < 1e-12 and abs(float(full[4])) < 1e-12
    assert abs(float(full[1]) - 0.5) < 1e-12  # mean of t over [0, 1]
    tiny = disc_band_factors(1e-3, 4)  # no cancellation for tiny discs
    torch.testing.assert_close(tiny, torch.ones(5, dtype=torch.float64), rtol=0, atol=1e-9)


def test_point_term_is_the_directional_light_and_ambient_is_ambient():
    got = light_from_words("key:az=25,el=-10,color=0.5/1/2,power=2", lmax=3)
    want = directional_light(camera_direction(25, -10), torch.tensor([1.0, 2.0, 4.0]), lmax=3)
    torch.testing.assert_close(got, want, rtol=1e-6, atol=1e-6)
    torch.testing.assert_close(light_from_words("ambient:0.2"), ambient_light(0.2))
    torch.testing.assert_close(light_from_words("ambient:color=1/0.5/0.25,power=2"),
                               ambient_light(torch.tensor([2.0, 1.0, 0.5])))


def test_terms_add_up_and_the_issue_example_loads_everywhere():
    parts = [light_from_words(t, 4) for t in ISSUE.split("+")]
    torch.testing.assert_close(light_from_words(ISSUE, 4), sum(parts), rtol=1e-6, atol=1e-6)
    sh = load_light(ISSUE)
    assert sh.shape == (9, 3) and sh.dtype == torch.float32
    assert load_light(ISSUE, lmax=4).shape == (25, 3)
    terms = parse_light_words(ISSUE)
    assert [t["kind"] for t in terms] == ["key", "fill", "ambient"]
    assert terms[0]["color"] == (1.0, 0.9, 0.8) and terms[0]["size"] == 20 and terms[2]["power"] == 0.2


def test_camera_terms():
    """Negative azimuth lights the image's left (−y in the light frame), positive elevation from above,
    azimuth 0 from the camera (+x)."""
    left = dominant_direction(light_from_words("key:az=-90,el=0"))
    assert float(left[1]) < -0.99
    top = dominant_direction(light_from_words("key:az=0,el=90"))
    assert float(top[2]) > 0.99
    front = dominant_direction(light_from_words("key:az=0,el=0,size=30"))
    assert float(front[0]) > 0.99
    # A surface facing the key is lit more than one facing away.
    sh = light_from_words("key:az=-40,el=30,size=20")
    n = torch.stack([camera_direction(-40, 30), -camera_direction(-40, 30)]).float()
    e = irradiance(sh, n)
    assert float(e[0, 0]) > 5 * float(e[1, 0].abs())


def test_envmap_drawing_holds_the_power():
    env = words_envmap("key:az=-40,el=30,size=20,power=3 + ambient:0.5", h=64)
    from relightnet.sh import latlong_directions

    _, sa = latlong_directions(64, 128, dtype=torch.float64)
    total = float((env[..., 0].double() * sa).sum())
    assert abs(total - (3 + 0.5 * 4 * math.pi)) < 1e-4 * total


@pytest.mark.parametrize("text,needle", [
    ("key:az=abc", "light term 1 'key:az=abc': az='abc' is not a number"),
    ("key:az=10 + lamp:az=3", "light term 2 'lamp:az=3': unknown kind 'lamp'"),
    ("key:el=100", "el=100 is out of range"),
    ("key:az=10,az=20", "az is given twice"),
    ("key:color=1/2", "color='1/2'"),
    ("fill:spread=3", "unknown parameter 'spread'"),
    ("ambient:az=10", "unknown parameter 'az'"),
    ("key:az=10 +", "light term 2: empty"),
    ("key:power=-1", "power=-1 is out of range"),
    ("key:size", "light term 1 'key:size': power='size' is not a number"),
])
def test_errors_name_the_term(text, needle):
    with pytest.raises(InputError) as e:
        load_light(text)
    assert needle in str(e.value)


def test_light_show_draws_words(tmp_path, capsys):
    out = tmp_path / "key.png"
    assert main(["light", "show", ISSUE, "--out", str(out), "--size", "48"]) == 0
    img = read_image(out)
    assert img.shape == (48, 48 * 6 + 12, 3)  # front, back, SH lat-long and the drawn discs
    front = img[:, :48].mean(-1)
    assert float(front[:, :20].mean()) > float(front[:, 28:].mean())  # the key is on the image's left
    assert main(["light", "show", "key:az=north", "--out", str(tmp_path / "bad.png")]) == 1
    assert "light term 1 'key:az=north'" in capsys.readouterr().err
    assert not (tmp_path / "bad.png").exists()
