import pytest
import torch

from relightnet.checks import InputError
from relightnet.color import linear_to_srgb, srgb_to_linear
from relightnet.light import light_from_words
from relightnet.pipeline.photo_colour import COLOUR_LIGHTS, chromaticity, colour_figures


def _photo(h=90, w=60, seed=0):
    g = torch.Generator().manual_seed(seed)
    smooth = torch.nn.functional.interpolate(torch.rand(1, 3, 6, 4, generator=g), size=(h, w), mode="bilinear")[0]
    photo = (0.2 + 0.6 * smooth + 0.02 * torch.rand(3, h, w, generator=g)).clamp(0, 1)
    mask = torch.zeros(h, w)
    mask[10:80, 15:45] = 1
    return photo, mask


def test_chromaticity_of_gray_black_and_red():
    x = torch.tensor([[0.5, 0.0, 1.0], [0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]).view(3, 1, 3)
    torch.testing.assert_close(chromaticity(x)[:, 0], torch.tensor([[1 / 3, 1 / 3, 1.0], [1 / 3, 1 / 3, 0.0]]))


def test_a_white_change_of_shading_moves_no_colour():
    photo, mask = _photo()
    same = colour_figures(photo, photo, mask)
    assert same["chroma_shift_p99"] == 0 and same["fine_chroma_ratio"] == pytest.approx(1.0)
    # A smooth white shading (brighter on the left), applied in linear RGB: chromaticity unchanged.
    ramp = torch.linspace(1.3, 0.4, photo.shape[2]).view(1, 1, -1)
    relit = linear_to_srgb((srgb_to_linear(photo) * ramp).clamp(0, 1))
    fig = colour_figures(photo, relit, mask)
    assert fig["chroma_shift_p99"] < 0.01 and fig["fine_chroma_ratio"] == pytest.approx(1.0, abs=0.05)


def test_colour_blotches_are_measured():
    photo, mask = _photo()
    lin = srgb_to_linear(photo)
    blotch = torch.zeros_like(mask)
    blotch[30:36, 20:26] = 1
    blotch[60:64, 30:40] = 1
    lin = lin * (1 + blotch * torch.tensor([-0.6, 0.8, -0.6]).view(3, 1, 1))  # green patches
    fig = colour_figures(photo, linear_to_srgb(lin.clamp(0, 1)), mask)
    assert fig["chroma_shift_p99"] > 0.15 and fig["fine_chroma_ratio"] > 1.5


def test_large_photos_are_shrunk_and_empty_people_refused():
    photo, mask = _photo(1600, 1000)
    assert colour_figures(photo, photo, mask)["chroma_shift_p99"] == 0
    tiny = torch.zeros_like(mask)
    tiny[5:9, 5:9] = 1  # eroded by 3 px: nothing left
    with pytest.raises(InputError, match="after eroding"):
        colour_figures(photo, photo, tiny)


def test_the_colour_lights_are_white_side_lights():
    for words in COLOUR_LIGHTS.values():
        light = light_from_words(words)
        torch.testing.assert_close(light[:, 0], light[:, 1])
        torch.testing.assert_close(light[:, 0], light[:, 2])
    left, right = (light_from_words(w) for w in COLOUR_LIGHTS.values())
    assert float(left[1, 0]) * float(right[1, 0]) < 0 or float(left[3, 0]) * float(right[3, 0]) < 0
