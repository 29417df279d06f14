"""Light switches seen in the frames' colour: a step of the whole frame found at its frame, fades and noise not."""

import pytest
import torch

from relightnet.checks import InputError
from relightnet.temporal import colour_switches, frame_colour
from relightnet.temporal.switches import COLOUR_STEP, merge_switches


def _colours(n=60, noise=0.002, seed=0):
    g = torch.Generator().manual_seed(seed)
    base = torch.tensor([0.4, 0.35, 0.3], dtype=torch.float64)
    return base * (1 + noise * torch.randn(n, 3, generator=g, dtype=torch.float64))


def test_frame_colour_is_the_mean_linear_colour_of_float_and_uint8_frames():
    img = torch.full((3, 8, 12), 0.5)
    lin = frame_colour(img)
    assert lin.shape == (3,) and lin.dtype == torch.float64
    assert torch.allclose(lin, torch.full((3,), ((0.5 + 0.055) / 1.055) ** 2.4, dtype=torch.float64))
    u8 = torch.full((3, 8, 12), 255, dtype=torch.uint8)
    assert torch.allclose(frame_colour(u8), torch.ones(3, dtype=torch.float64))
    with pytest.raises(Exception, match="frame"):
        frame_colour(torch.zeros(8, 12))


def test_a_step_of_the_light_is_found_at_its_frame():
    c = _colours()
    c[37:] *= torch.tensor([0.75, 0.62, 0.45], dtype=torch.float64)  # dimmer and warmer
    assert colour_switches(c).nonzero().flatten().tolist() == [37]
    # a single odd frame (a flash) is no switch, nor is noise
    c = _colours()
    c[20] *= 2.0
    assert not colour_switches(c).any()
    assert not colour_switches(_colours(noise=0.02)).any()


def test_a_fade_and_a_small_step_are_no_switch():
    c = _colours(noise=0.0005)
    c *= torch.linspace(1.0, 0.4, 60, dtype=torch.float64)[:, None]  # the light fades over two seconds
    assert not colour_switches(c).any()
    c = _colours(noise=0.0005)
    c[30:] *= 1 + 0.5 * COLOUR_STEP  # below the smallest step taken
    assert not colour_switches(c).any()
    c[30:] *= 1 + 2 * COLOUR_STEP
    assert colour_switches(c).nonzero().flatten().tolist() == [30]


def test_short_clips_and_bad_options():
    assert not colour_switches(_colours(n=8)).any()
    with pytest.raises(InputError, match="colour switches"):
        colour_switches(_colours(), window=0)
    with pytest.raises(Exception, match="frame colours"):
        colour_switches(torch.ones(10))


def test_merge_keeps_the_colours_frame_for_one_switch_found_twice():
    lights, colour = torch.zeros(40, dtype=torch.bool), torch.zeros(40, dtype=torch.bool)
    lights[[12, 30]] = True
    colour[10] = True
    assert merge_switches(lights, colour).nonzero().flatten().tolist() == [10, 30]
    assert torch.equal(merge_switches(lights, None), lights)
