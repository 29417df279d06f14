"""Procedural light families: skies, windows, mixtures — seeded, finite, normalised like every light."""

import math

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.data import SynthConfig
from relightnet.data.light_families import FAMILIES, family_light, perez_sky, preetham_zenith, xyY_to_rgb
from relightnet.data.lights import LIGHT_SOURCES, light_at, light_level, sample_light
from relightnet.sh import irradiance
from relightnet.sh.metrics import dominant_direction


@pytest.mark.parametrize("kind", FAMILIES)
def test_families_are_seeded_and_finite(kind):
    a, pa = family_light(kind, np.random.default_rng(5), 2, ("city", "studio"))
    b, pb = family_light(kind, np.random.default_rng(5), 2, ("city", "studio"))
    assert a.shape == (9, 3) and torch.isfinite(a).all()
    assert torch.equal(a, b) and pa == pb
    assert float(a[0].min()) > 0  # some light of every colour


@pytest.mark.parametrize("kind", ["preetham", "window", "mixture"])
def test_sample_light_normalises_the_families(kind):
    rng = np.random.default_rng(0)
    for _ in range(5):
        d = sample_light(rng, ("city",), 2, mix={kind: 1.0})
        assert d.source == kind
        assert light_level(d.base) == pytest.approx(1.0, rel=1e-6)
        L = light_at(d).double()
        n = torch.randn(200, 3, dtype=torch.float64)
        E = irradiance(L, n / n.norm(dim=1, keepdim=True), check=False)
        assert float(E.min()) > -1e-6  # lifted: no negative irradiance


def test_a_clear_sky_is_lit_from_the_sun():
    rng = np.random.default_rng(3)
    for _ in range(20):
        sh, p = family_light("preetham", rng, 2)
        if p["overcast"] or p["sun_to_sky"] < 2:
            continue
        e, a = math.radians(p["sun_elevation_deg"]), math.radians(p["sun_azimuth_deg"])
        sun = torch.tensor([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)], dtype=torch.float64)
        assert float(dominant_direction(sh) @ sun) > 0.7


def test_preetham_formulas():
    # zenith luminance grows with turbidity; the Perez function is 1 + C + E at the zenith for a sun at 0°
    assert preetham_zenith(6.0, 0.5)[2] > preetham_zenith(2.0, 0.5)[2]
    x, y, _ = preetham_zenith(2.5, 0.3)
    assert 0.2 < x < 0.4 and 0.2 < y < 0.4  # a bluish-white sky
    white = xyY_to_rgb(0.3127, 0.3290, 1.0)  # D65 white is neutral in sRGB
    assert np.allclose(white / white.mean(), 1.0, atol=0.01)
    f = perez_sky(np.array(1.0), np.array(0.0), (0.0, 0.0, 2.0, 0.0, 0.5))
    assert float(f) == pytest.approx(1 + 2 + 0.5)


def test_light_mix_is_validated_and_reproducible():
    with pytest.raises(InputError, match="light_mix"):
        SynthConfig(light_mix={"laser": 1.0})
    with pytest.raises(InputError, match="light_mix"):
        SynthConfig(light_mix={"hdri": 0.0})
    with pytest.raises(InputError, match="clip_lights"):
        SynthConfig(clip_lights="sometimes")
    cfg = SynthConfig(light_mix={k: 1.0 for k in LIGHT_SOURCES})
    assert SynthConfig.from_dict(cfg.to_dict()) == cfg
    rng = np.random.default_rng(9)
    seen = {sample_light(rng, ("city",), 2, mix=cfg.light_mix).source for _ in range(60)}
    assert seen == set(LIGHT_SOURCES)
