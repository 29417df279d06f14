"""The capture job's pieces: the fit's masks frame by frame, the source's light (the shipped CNN)."""

import pytest
import torch

from relightnet.checks import InputError
from relightnet.fit.masks import PackedMasks
from relightnet.pipeline.capture_job import frame_masks, source_lights


def test_frame_masks_come_back_at_the_frame_size_one_at_a_time():
    m = torch.zeros(3, 40, 30, dtype=torch.bool)
    m[0, 10:30, 5:20] = True
    m[2, 0:5, 0:5] = True
    got = list(frame_masks(PackedMasks.from_masks(m), 3))
    assert got[1] is None and torch.equal(got[0], m[0]) and torch.equal(got[2], m[2])


def test_source_lights_fill_frames_without_a_person_and_refuse_none():
    from relightnet.pipeline.backends import make_predictor

    predictor = make_predictor("torch", None, "cpu")  # the shipped CNN
    frames = [torch.full((3, 64, 48), v) for v in (0.2, 0.4, 0.6)]
    mask = torch.zeros(64, 48, dtype=torch.bool)
    mask[8:60, 14:34] = True
    lights = source_lights(predictor, frames, [mask, None, mask], "auto", 30.0)
    assert lights.shape == (3, 9, 3) and bool(torch.isfinite(lights).all())
    with pytest.raises(InputError, match="no frame shows a person"):
        source_lights(predictor, frames, [None] * 3, "auto", 30.0)
