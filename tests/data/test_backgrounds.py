"""relightnet.data.backgrounds: procedural backgrounds at a set luminance, env-map views, the blur."""

import math

import numpy as np
import pytest
import torch

from relightnet.data.backgrounds import envmap_background, gaussian_blur, procedural_background
from relightnet.data.lights import LUMA


def test_gaussian_blur_keeps_the_mean_and_spreads_an_impulse():
    img = torch.zeros(31, 31, 3)
    img[15, 15] = 1.0
    out = gaussian_blur(img, 2.0)
    assert out.shape == img.shape and out.sum().item() == pytest.approx(3.0, rel=1e-4)
    prof = out[15, :, 0]
    assert prof.argmax() == 15 and prof[15 + 2] / prof[15] == pytest.approx(math.exp(-0.5), rel=0.02)
    assert torch.equal(gaussian_blur(img, 0.2), img)  # below a third of a pixel: unchanged


def test_procedural_backgrounds_hit_their_luminance_and_reproduce():
    for seed in range(8):
        img, desc = procedural_background(np.random.default_rng(seed), 48, level=0.3)
        again, desc2 = procedural_background(np.random.default_rng(seed), 48, level=0.3)
        assert torch.equal(img, again) and desc == desc2
        assert img.shape == (48, 48, 3) and img.dtype == torch.float32 and img.min() >= 0
        lum = (img * torch.as_tensor(LUMA, dtype=img.dtype)).sum(-1).mean().item()
        assert lum == pytest.approx(0.3, rel=0.05)


def test_envmap_view_of_a_constant_map_is_the_gain():
    env = torch.full((16, 32, 3), 0.5)
    img = envmap_background(env, (20.0, 20.0, 12.0, 12.0), 24, torch.eye(3), gain=(2.0, 1.0, 0.5), blur_px=1.5)
    assert img.shape == (24, 24, 3)
    assert torch.allclose(img, torch.tensor([1.0, 0.5, 0.25]).expand(24, 24, 3), atol=1e-5)


def test_envmap_view_sees_the_map_behind_the_subject():
    # the default camera looks along -z: the centre of its view is the centre column of the lat-long map
    env = torch.zeros(32, 64, 3)
    env[12:20, 28:36] = 1.0  # a bright patch at the map's centre (direction -z)
    img = envmap_background(env, (30.0, 30.0, 16.0, 16.0), 32, torch.eye(3), gain=1.0)
    assert img[14:18, 14:18].min() > 0.9 and img[0, 0].max() < 0.1
