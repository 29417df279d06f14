"""The added-flicker ratio and the warp error of a processed video against its source."""

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.pipeline.flicker import FlickerMeter


def _frames(n=6, seed=0):
    g = torch.Generator().manual_seed(seed)
    base = torch.nn.functional.interpolate(torch.rand(1, 3, 8, 12, generator=g), size=(64, 120), mode="bicubic",
                                           align_corners=False)[0].clamp(0, 1)
    return [(base[:, :, 2 * t:2 * t + 96].permute(1, 2, 0).numpy() * 255).round().astype(np.uint8) for t in range(n)]


def test_an_unchanged_video_adds_no_flicker_and_a_flickering_one_does():
    src = _frames()
    mask = np.ones(src[0].shape[:2], bool)
    same = FlickerMeter()
    for f in src:
        same.update(f, f, mask)
    r = same.result()
    assert r["added_flicker"] == pytest.approx(1.0) and r["warp_error"] == pytest.approx(r["source_warp_error"])
    assert r["pairs"] == len(src) - 1
    noisy = FlickerMeter()
    for t, f in enumerate(src):
        gain = 1.15 if t % 2 else 0.85  # the whole person brightens and darkens frame to frame
        noisy.update(f, np.clip(f * gain, 0, 255).astype(np.uint8), mask)
    n = noisy.result()
    assert n["added_flicker"] > 1.3 and n["warp_error"] > 2 * r["warp_error"]


def test_no_person_in_two_frames_and_bad_shapes():
    src = _frames(2)
    empty = FlickerMeter()
    for f in src:
        empty.update(f, f, np.zeros(f.shape[:2], bool))
    with pytest.raises(InputError, match="no two consecutive"):
        empty.result()
    with pytest.raises(InputError, match="expected"):
        FlickerMeter().update(src[0], src[0][:10], np.ones(src[0].shape[:2], bool))
