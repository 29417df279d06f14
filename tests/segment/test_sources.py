"""The one rule for a command's person mask: the user's mask, else a photo's alpha, else segmentation or the head."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from people import iou

from relightnet.checks import InputError
from relightnet.io import VideoWriter
from relightnet.segment import person_mask, video_masks


def test_photo_rule(person_scene, person_models):
    img, truth = person_scene
    given = torch.zeros_like(truth)
    given[:10, :10] = 1
    assert person_mask(img, given, truth, models=person_models) is given  # the user's mask wins
    assert torch.equal(person_mask(img, None, truth * 0.9, models=person_models), truth)  # then the alpha
    assert person_mask(img, source="head", models=person_models) is None  # the CNN's mask head
    assert iou(person_mask(img, models=person_models), truth) > 0.9  # the segmentation (default)
    with pytest.raises(InputError, match="mask source"):
        person_mask(img, source="magic")


@pytest.mark.slow
def test_video_rule(walking_clip, masked_clip, person_models, tmp_path):
    frames, truth = walking_clip
    video = tmp_path / "walk.mkv"
    with VideoWriter(video, fps=10) as w:
        for f in frames:
            w.write((f.permute(1, 2, 0) * 255).round().to(torch.uint8).numpy())
    info, n, pairs = video_masks(video, models=person_models)
    got = list(pairs)
    assert len(got) == len(frames) and all(iou(m, t) > 0.85 for (_, _, m), t in zip(got, truth, strict=True))
    _, _, pairs = video_masks(video, source="head")
    assert all(m is None for _, _, m in pairs)
    (tmp_path / "given").mkdir()
    clip, masks = masked_clip(tmp_path / "given")
    _, n, pairs = video_masks(clip, masks)  # given masks win
    assert n == 3 and all(m.any() for _, _, m in pairs)
    # A video with no person: one line naming the video and the frame.
    empty = tmp_path / "empty.mkv"
    with VideoWriter(empty, fps=10) as w:
        for _ in range(2):
            w.write(np.full((120, 160, 3), 90, np.uint8))
    with pytest.raises(InputError, match=r"empty\.mkv: frame 0 \(counting from 0\): no person found"):
        list(video_masks(empty, models=person_models)[2])
    _, _, pairs = video_masks(empty, allow_empty=True, models=person_models)
    assert all(not m.any() for _, _, m in pairs)
