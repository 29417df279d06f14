import sys
from pathlib import Path

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.fit import Observations, observe_frames
from relightnet.fit.observe import fill_missing, world_to_view_axes
from relightnet.fit.terms import silhouette_targets

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "fuzz"))
from resource_fit import person_clip  # noqa: E402  (the fit's resource cases render the same person)

sys.path.pop(0)


def _obs(found):
    T = len(found)
    lm = torch.zeros(T, 33, 5)
    lm[..., 0] = torch.arange(T, dtype=torch.float32)[:, None] * 10
    lm[..., 3:] = 1.0
    return Observations(lm, torch.zeros(T, 33, 3), torch.zeros(T, 8, 8), torch.tensor(found), (8, 8))


def test_missing_frames_are_interpolated_held_and_down_weighted():
    out = fill_missing(_obs([False, True, False, False, True, False]))
    x = out.landmarks[:, 0, 0]
    torch.testing.assert_close(x, torch.tensor([10.0, 10.0, 20.0, 30.0, 40.0, 40.0]))
    assert torch.equal(out.landmarks[:, 0, 3], torch.tensor([0.5, 1.0, 0.5, 0.5, 1.0, 0.5]))
    assert torch.equal(out.found, torch.tensor([False, True, False, False, True, False]))  # still flagged


def test_no_person_anywhere_is_an_error():
    with pytest.raises(InputError, match="clip.mp4: no person found in any frame"):
        fill_missing(_obs([False, False]), name="clip.mp4")


def test_world_axes():
    assert torch.equal(world_to_view_axes(torch.tensor([1.0, 2.0, 3.0])), torch.tensor([1.0, -2.0, -3.0]))


def test_float_masks_given_are_packed_and_checked():
    T = 3
    masks = torch.zeros(T, 8, 8)
    masks[1, 2:5, 3:7] = 1.0
    obs = Observations(torch.zeros(T, 33, 5), torch.zeros(T, 33, 3), masks, torch.ones(T, dtype=torch.bool), (8, 8))
    assert torch.equal(obs.masks.unpack(), masks > 0.5)
    assert torch.equal(obs.slice(1, 3).masks.unpack(), masks[1:3] > 0.5)
    with pytest.raises(ShapeError, match=r"masks: expected 2 masks of \(8, 8\), got 3"):
        Observations(torch.zeros(2, 33, 5), torch.zeros(2, 33, 3), obs.masks, torch.ones(2, dtype=torch.bool), (8, 8))


@pytest.mark.slow  # a clip rendered and segmented
def test_a_clips_packed_evidence_is_the_old_full_size_evidence_bit_for_bit(tmp_path, fit_body):
    """The fit keeps a video's masks packed at its working resolution now (each window of frames resampled as
    soon as it is segmented), not as one float (H, W) mask per frame. On a generated clip of a walking person
    (real segmentation) of 480 × 384, where the person is taller than the working 240 px, every window's
    silhouette evidence, the only thing the optimiser reads from the masks, equals what the old full-size float
    masks gave, bit for bit: the fit is unchanged."""
    from relightnet.fit.job import media_frames
    from relightnet.fit.masks import PackedMasks
    from relightnet.fit.solve import _window_evidence
    from relightnet.segment import PersonModels
    from relightnet.segment.video import track_person

    clip = tmp_path / "clip.mp4"
    person_clip(clip, 5, small=(240, 192), up=2)
    models = PersonModels(threads=1)
    old = torch.stack([res.mask.float() if res is not None else torch.zeros(480, 384)  # the old observe_frames
                       for _, res in track_person(media_frames(clip)[0], models)])
    obs = observe_frames(media_frames(clip)[0], models, name="clip.mp4", window=2)
    assert bool(obs.found.all()) and old.shape == (5, 480, 384) and 0.03 < float(old.mean()) < 0.5
    assert obs.masks.nbytes < PackedMasks.from_masks(old).nbytes  # windows of 2 kept at the working resolution
    for a in range(0, 5, 2):  # windows of 2 frames, the last one short
        new = _window_evidence(fit_body, obs, a, a + 2).silhouette
        ref = silhouette_targets(old[a:a + 2], size=obs.size)  # the same steps on the old float masks
        assert new.outside.shape[-2] < 480  # resampled
        assert torch.equal(new.outside, ref.outside) and torch.equal(new.outline, ref.outline)
        assert torch.equal(new.valid, ref.valid) and new.factor == ref.factor
