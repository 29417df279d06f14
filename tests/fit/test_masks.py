"""Packed masks: bit for bit what was appended, and small where a float mask per frame was not."""

import numpy as np
import pytest
import torch
import torch.nn.functional as F

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


def _old_working(masks: np.ndarray, height: int) -> tuple[np.ndarray, tuple[float, float]]:
    """What the fit did before with a window's full-size masks (``terms._working_masks`` until the masks were
    kept at the working resolution): the person's rows over the window set the scale, each frame area-averaged."""
    T, H, W = masks.shape
    rows = np.flatnonzero(masks.any(2).any(0))
    person = float(rows.max() - rows.min() + 1) if len(rows) else float(H)
    r = min(1.0, height / person, 1.0)
    h, w = max(1, round(H * r)), max(1, round(W * r))
    if (h, w) == (H, W):
        return masks, (w / W, h / H)
    out = np.stack([(F.interpolate(torch.from_numpy(m).float()[None, None], size=(h, w), mode="area")[0, 0]
                     > 0.5).numpy() for m in masks])
    return out, (w / W, h / H)


@pytest.mark.parametrize("window", [1, 3, 4])
def test_masks_kept_at_the_working_resolution_are_what_the_fit_resampled_before(window):
    """Packed for the fit's window, each complete window is resampled when its last frame arrives, the last
    (short) one when the fit asks: every window's working masks, and the silhouette evidence made from them,
    equal the old path's on the full-size masks bit for bit."""
    from relightnet.fit.terms import silhouette_targets

    m = _blobs(10, (96, 72), seed=3)
    m[5] = False  # a frame where nobody was found
    height = 20  # the person's working height: every window is resampled (persons are taller)
    packed = PackedMasks((96, 72), window=window, height=height)
    for t in range(10):
        packed.append_empty() if t == 5 else packed.append(torch.from_numpy(m[t]))
    for a in range(0, 10, window):
        b = min(a + window, 10)
        work, factor = packed[a:b].working()
        ref, ref_factor = _old_working(m[a:b], height)
        assert work.shape[1] < 96  # resampled
        assert torch.equal(work, torch.from_numpy(ref)) and factor == ref_factor
        new = silhouette_targets(work, size=(96, 72), height=None)
        old = silhouette_targets(torch.from_numpy(m[a:b]).float(), size=(96, 72), height=height)
        assert torch.equal(new.outside, old.outside) and torch.equal(new.outline, old.outline)
        assert torch.equal(new.valid, old.valid) and new.factor == old.factor
    assert packed.nbytes < PackedMasks.from_masks(m).nbytes  # smaller than the full-size masks


def test_a_noise_mask_at_the_pixel_limit_costs_at_most_the_working_box():
    """Masks that do not compress (random bits) in 4000 × 3120 frames (12.5 MP): 1.5 MB a frame at the frame's
    size, at most MAX_FRAME_BYTES (~28.5 KiB) at the working resolution; the band as wide as 4 persons are tall
    reaches the largest working box (240 × 960 bits), so the bound is the worst case, not a loose one."""
    from relightnet.fit.masks import MAX_FRAME_BYTES

    H, W = 3120, 4000
    rng = np.random.default_rng(0)
    packed = PackedMasks((H, W), window=1)
    for y0, y1 in ((0, H), (1000, 2000), (1500, 1700)):  # the whole frame, a 1000-row band, a 200-row band
        m = np.zeros((H, W), bool)
        m[y0:y1] = rng.random((y1 - y0, W), dtype=np.float32) < 0.5
        packed.append(m)
        del m
    sizes = [len(it[1]) for it in packed._items]
    assert max(sizes) <= MAX_FRAME_BYTES < 30_000, sizes
    assert sizes[1] > 0.8 * MAX_FRAME_BYTES, sizes  # 240 × 960 random bits
    assert packed.nbytes <= 3 * MAX_FRAME_BYTES
