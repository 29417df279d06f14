"""RelightSession: the CNN once, then re-shading only — the same picture as relight-image."""

import numpy as np
import pytest
import torch

from relightnet.app.session import RelightSession, load_photo
from relightnet.checks import InputError
from relightnet.io import write_image
from relightnet.light import load_light
from relightnet.pipeline.relight_image import relight_image
from relightnet.segment.matte import band_radius, border_band

LIGHTS = ["key:az=-40,el=30,size=20,color=1/0.9/0.8,power=3 + fill:az=60,el=10,power=0.5 + ambient:0.2",
          "studio", "key:az=170,el=-20,size=5"]


@pytest.fixture(scope="module")
def relighter(predictor, person_photo):
    return RelightSession(predictor, load_photo(person_photo))


@pytest.mark.slow
@pytest.mark.parametrize("words", LIGHTS)
def test_same_picture_as_relight_image(relighter, predictor, words):
    light = load_light(words)
    cli = relight_image(predictor, relighter.photo.image, light, relighter.photo.mask).image
    got = relighter.relight(light)
    # the same formulas in another order: float32 rounding, far below one 8-bit level
    torch.testing.assert_close(got, cli, rtol=0, atol=1e-4)
    live = relighter.relight_u8(light).float()
    assert float((live - (cli * 255).round()).abs().max()) <= 1  # the live view's sRGB table
    mask = relighter.prediction.mask[0, 0]
    outside = (mask == 0) & ~border_band(mask, band_radius(*mask.shape))  # the soft edge stays in its band
    assert torch.equal(got[outside], relighter.photo.image.permute(1, 2, 0)[outside])


def test_the_cnn_runs_once(relighter, predictor, monkeypatch):
    def boom(*a, **k):
        raise AssertionError("the CNN ran again")

    monkeypatch.setattr(type(predictor), "__call__", boom)
    a = relighter.relight(load_light("key:az=-60,el=20"))
    b = relighter.relight(load_light("key:az=60,el=20"))
    assert float((a - b).abs().max()) > 0.05


def test_bad_photos_are_refused_with_the_cli_message(tmp_path, monkeypatch):
    from relightnet.io.limits import max_pixels, set_max_pixels

    big = tmp_path / "big.png"
    write_image(big, np.zeros((64, 64, 3), np.uint8))
    old = max_pixels()
    set_max_pixels(1000)
    try:
        with pytest.raises(InputError, match="pixels"):
            load_photo(big)
    finally:
        set_max_pixels(old)
    with pytest.raises(InputError):
        load_photo(tmp_path / "missing.png")
