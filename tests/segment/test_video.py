"""Tracked person masks on a generated person walking over a real photograph."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from people import flip_rate, iou

from relightnet.checks import InputError
from relightnet.segment import PersonTracker, track_person

pytestmark = pytest.mark.slow  # person tracking over a rendered walking clip


def test_tracked_masks_are_accurate_and_as_stable_as_the_true_ones(walking_clip, person_models):
    frames, truth = walking_clip
    masks = [res.mask for _, res in track_person(frames, person_models)]
    assert min(iou(m, t) for m, t in zip(masks, truth, strict=True)) > 0.85
    # The bound: at most 1.5 x the flip rate of exact (hand-made-like) masks.
    assert flip_rate(masks) <= 1.5 * flip_rate(truth)


def test_tracker_finds_the_person_again_after_losing_them(walking_clip, person_models):
    frames, truth = walking_clip
    empty = torch.zeros_like(frames[0])
    tracker = PersonTracker(person_models)
    assert tracker(frames[0]) is not None
    assert tracker(empty) is None  # lost
    again = tracker(frames[2])
    assert again is not None and iou(again.mask, truth[2]) > 0.85


def test_frame_without_a_person_is_named(walking_clip, person_models):
    frames, _ = walking_clip
    clip = [frames[0], torch.zeros_like(frames[0])]
    with pytest.raises(InputError, match=r"^clip\.mp4: frame 1 \(counting from 0\): no person found"):
        list(track_person(clip, person_models, allow_empty=False, name="clip.mp4"))
    assert [r is None for _, r in track_person(clip, person_models)] == [False, True]
    with pytest.raises(InputError, match="smoothing"):
        PersonTracker(person_models, smoothing=0)


def test_steady_masks_are_as_stable_as_exact_ones_and_as_accurate(walking_clip, person_models):
    # A short walk whose outline barely shimmers unfiltered: the filter must not make it worse
    # (it feeds back into the next crop, so the flips are not exactly the unfiltered ones).
    frames, truth = walking_clip
    runs = {m: [res.mask for _, res in track_person(frames, person_models, steady=m)] for m in (0.0, 0.15)}
    ious = {m: np.mean([iou(a, t) for a, t in zip(masks, truth, strict=True)]) for m, masks in runs.items()}
    assert flip_rate(runs[0.15]) <= min(1.02 * flip_rate(runs[0.0]), 1.2 * flip_rate(truth))
    assert ious[0.15] >= ious[0.0] - 0.005
