"""Packed masks: bit for bit what was appended, and small where a float mask per frame was not."""

import numpy as np
import pytest
import torch

from relightnet.checks import ShapeError
from relightnet.fit.masks import PackedMasks


def _blobs(T: int, size, seed: int = 0) -> np.ndarray:
    """(T, H, W) bool: random ellipses, one frame empty, one full (the box is the whole frame)."""
    rng = np.random.default_rng(seed)
    H, W = size
    y, x = np.mgrid[:H, :W]
    out = np.zeros((T, H, W), bool)
    for t in range(T):
        cy, cx = rng.uniform(0, H), rng.uniform(0, W)
        ry, rx = rng.uniform(1, max(H / 2, 2)), rng.uniform(1, max(W / 2, 2))
        out[t] = ((y - cy) / ry) ** 2 + ((x - cx) / rx) ** 2 < 1
    out[1] = False
    out[2] = True
    return out


@pytest.mark.parametrize("size", [(37, 53), (64, 64), (1, 9), (9, 1)])
def test_unpack_gives_back_every_bit(size):
    m = _blobs(6, size)
    m[3] = np.random.default_rng(1).random(size) < 0.5  # no runs at all: every bit of a noisy box
    packed = PackedMasks.from_masks(torch.from_numpy(m).float())  # values in {0, 1}: above 0.5 is the person
    assert len(packed) == 6 and packed.size == size
    assert torch.equal(packed.unpack(), torch.from_numpy(m))
    assert torch.equal(packed[2:5].unpack(), torch.from_numpy(m[2:5]))  # a window of frames


def test_appended_frames_and_empty_frames():
    m = _blobs(3, (20, 30))
    packed = PackedMasks((20, 30))
    packed.append(torch.from_numpy(m[0]))
    packed.append_empty()
    packed.append(m[2].astype(np.float32))  # an array of {0, 1}
    assert torch.equal(packed.unpack(), torch.from_numpy(np.stack([m[0], np.zeros_like(m[0]), m[2]])))
    with pytest.raises(ShapeError, match=r"mask: expected shape \(20, 30\), got \(30, 20\)"):
        packed.append(np.zeros((30, 20), bool))
    with pytest.raises(ShapeError, match=r"masks: expected \(T, H, W\)"):
        PackedMasks.from_masks(np.zeros((20, 30), bool))


def test_a_person_at_the_pixel_limit_costs_its_outline_not_its_area():
    """A person-sized ellipse in a 4000 × 3120 frame: 50 MB as the float32 mask the fit once kept, 1.6 MB as
    the box's bits; deflated, the rows' two runs each leave a few bytes per row (3,120 rows: < 64 KB)."""
    H, W = 3120, 4000
    y, x = np.ogrid[:H, :W]
    person = ((y - 1600) / 1300.0) ** 2 + ((x - 2000) / 500.0) ** 2 < 1
    packed = PackedMasks((H, W))
    packed.append(person)
    assert packed.nbytes < 64 << 10
    assert torch.equal(packed.unpack()[0], torch.from_numpy(person))
