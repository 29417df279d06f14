import pytest
import torch

from relightnet.checks import InputError
from relightnet.fit import Observations, fill_missing, world_to_view_axes


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
