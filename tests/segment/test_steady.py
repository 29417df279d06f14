"""The temporal mask filter: hysteresis on the probability, with the previous mask carried along the motion."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.segment import PersonMask, PersonTracker
from relightnet.segment.steady import carry_mask, hysteresis, landmark_motion, near_outline
from relightnet.segment.video import steady_person

H, W = 120, 200


def _disc(cx: float, cy: float, r: float = 30.0, soft: float = 1.5) -> torch.Tensor:
    """(H, W) probability of a disc with a logistic edge ``soft`` pixels wide."""
    y, x = torch.meshgrid(torch.arange(H) + 0.5, torch.arange(W) + 0.5, indexing="ij")
    return torch.sigmoid((r - ((x - cx) ** 2 + (y - cy) ** 2).sqrt()) / soft)


def _landmarks(cx: float, cy: float) -> torch.Tensor:
    """(33, 5) landmarks on a ring around (cx, cy), all seen."""
    a = torch.linspace(0, 2 * np.pi, 34)[:33]
    lm = torch.ones(33, 5)
    lm[:, 0], lm[:, 1], lm[:, 2] = cx + 20 * a.cos(), cy + 20 * a.sin(), 0
    return lm


def _result(prob: torch.Tensor, lm: torch.Tensor) -> PersonMask:
    return PersonMask((prob > 0.5).float(), prob, (W / 2, H / 2, float(W)), lm, torch.zeros(33, 3), 1.0)


def _run(probs, lms, margin: float) -> list[torch.Tensor]:
    prev, masks = None, []
    for p, lm in zip(probs, lms, strict=True):
        prev = steady_person(_result(p, lm), prev, margin)
        masks.append(prev.mask)
    return masks


def _flips(masks) -> float:
    return float(np.mean([float((a != b).float().mean()) for a, b in zip(masks[:-1], masks[1:], strict=True)]))


def _iou(a, b) -> float:
    a, b = a > 0.5, b > 0.5
    return float((a & b).sum()) / float((a | b).sum())


def test_a_static_mask_is_kept_as_it_is():
    p = _disc(100, 60)
    masks = _run([p] * 5, [_landmarks(100, 60)] * 5, 0.15)
    assert all(torch.equal(m, (p > 0.5).float()) for m in masks)


def test_single_frame_flicker_at_the_outline_is_removed():
    g = torch.Generator().manual_seed(0)
    base = _disc(100, 60)
    band = (base - 0.5).abs() < 0.3
    probs = [(base + band * (torch.rand(H, W, generator=g) - 0.5) * 0.3).clamp(0, 1) for _ in range(12)]
    lms = [_landmarks(100, 60)] * 12
    raw, steady = _run(probs, lms, 0.0), _run(probs, lms, 0.15)
    assert _flips(steady) < 0.25 * _flips(raw)
    truth = (base > 0.5).float()
    assert min(_iou(m, truth) for m in steady) > 0.97


@pytest.mark.parametrize("follow", [True, False])
def test_a_moving_part_is_not_dragged(follow):
    # A disc moving 10 px a frame; the landmarks follow it (the body moves) or stay (a limb moves alone).
    xs = [40.0 + 10 * t for t in range(12)]
    probs = [_disc(x, 60) for x in xs]
    lms = [_landmarks(x if follow else 40.0, 60) for x in xs]
    truth = [(p > 0.5).float() for p in probs]
    raw, steady = _run(probs, lms, 0.0), _run(probs, lms, 0.15)
    iou_raw = np.mean([_iou(m, t) for m, t in zip(raw, truth, strict=True)])
    iou_steady = np.mean([_iou(m, t) for m, t in zip(steady, truth, strict=True)])
    if follow:  # the carried mask moves with the disc: nothing lags
        assert iou_steady >= iou_raw - 1e-6
    else:  # only the uncertain band (|p - 0.5| < margin, ~1 px here) near the old outline keeps its state
        assert iou_steady >= iou_raw - 0.04
    for p, m in zip(probs, steady, strict=True):  # confident pixels always follow the current frame
        assert bool(m[p > 0.65].all()) and not bool(m[p < 0.35].any())


def test_first_frame_and_margin_zero_are_untouched():
    res = _result(_disc(100, 60), _landmarks(100, 60))
    assert steady_person(res, None, 0.15) is res
    assert steady_person(res, res, 0.0) is res
    assert torch.equal(hysteresis(res.probability, None, 0.15), res.probability > 0.5)


def test_carry_and_motion_shapes():
    lm = _landmarks(100, 60)
    moved = lm.clone()
    moved[:, :2] = 1.1 * lm[:, :2] + torch.tensor([3.0, -2.0])
    assert landmark_motion(lm, moved) == pytest.approx((1.1, 1.1, 3.0, -2.0), abs=1e-4)
    squeezed = lm.clone()
    squeezed[:, 0] = 0.9 * lm[:, 0] + 10  # a person turning: narrower, as tall
    assert landmark_motion(lm, squeezed) == pytest.approx((0.9, 1.0, 10.0, 0.0), abs=1e-4)
    hidden = lm.clone()
    hidden[2:, 3] = 0.1
    assert landmark_motion(hidden, lm) is None  # fewer than 3 seen in both
    mask = _disc(100, 60) > 0.5
    out = carry_mask(mask.float(), (1.0, 1.0, 10.0, 0.0), (0, 0, 150, H))
    assert out.shape == (H, W) and out.dtype == torch.bool
    assert torch.equal(out[:, 10:150], mask[:, :140])
    assert not out[:, 150:].any() and not out[:, :10].any()  # outside the window; nothing came from x < 0
    grown = carry_mask(mask.float(), (2.0, 2.0, -100.0, -60.0))  # twice the size about (100, 60)
    assert abs(float(grown.float().sum()) / float(mask.float().sum()) - 4) < 0.05
    with pytest.raises(InputError, match="landmarks"):
        landmark_motion(lm[:, :4], lm[:, :4])


def test_tracker_refuses_a_bad_margin(person_models):
    for bad in (-0.1, 0.5):
        with pytest.raises(InputError, match="steady"):
            PersonTracker(person_models, steady=bad)


def test_near_outline_is_the_square_holding_person_and_background():
    """Against the definition, pixel by pixel: the (2 r + 1)² square around a pixel holds a person pixel and a
    background pixel, outside the frame counting as background (random masks, sizes and reaches)."""
    rng = np.random.default_rng(0)
    for _ in range(20):
        h, w = (int(v) for v in rng.integers(1, 40, 2))
        r = int(rng.integers(0, 7))
        fg = rng.random((h, w)) < rng.random()
        padded = np.pad(fg, r)
        want = np.zeros((h, w), bool)
        for y in range(h):
            for x in range(w):
                square = padded[y:y + 2 * r + 1, x:x + 2 * r + 1]
                want[y, x] = square.any() and not square.all()
        got = near_outline(torch.from_numpy(fg.astype(np.float32)), r)
        assert got.dtype == torch.bool and got.shape == (h, w)
        np.testing.assert_array_equal(got.numpy(), want)


def _textured(cx: float, seed: int = 0) -> np.ndarray:
    """(H, W) uint8 gray frame: a static textured background and a disc at x = cx with its own texture moving
    with it (what optical flow follows)."""
    g = torch.Generator().manual_seed(seed)
    bg = torch.nn.functional.interpolate(torch.rand(1, 1, 12, 20, generator=g), size=(H, W), mode="bicubic",
                                         align_corners=False)[0, 0]
    fg = torch.nn.functional.interpolate(torch.rand(1, 1, 8, 8, generator=g), size=(80, 80), mode="bicubic",
                                         align_corners=False)[0, 0] * 0.5 + 0.5
    img = bg.clone() * 0.4
    d = _disc(cx, 60) > 0.5
    x0 = int(round(cx)) - 40
    ys, xs = torch.nonzero(d, as_tuple=True)
    img[ys, xs] = fg[(ys - 20).clamp(0, 79), (xs - x0).clamp(0, 79)]
    return (img.clamp(0, 1) * 255).round().to(torch.uint8).numpy()


def test_flow_carries_the_mask_with_what_moves():
    from relightnet.segment.steady import flow_carry

    prev, cur = _textured(90), _textured(96)
    soft, rel = flow_carry(prev, cur, (_disc(90, 60) > 0.5).float(), (0, 0, W, H))
    assert soft.shape == (H, W) and rel.shape == (H, W)
    assert _iou(torch.from_numpy(soft), _disc(96, 60)) > 0.9  # moved 6 px with the disc, not left behind
    assert _iou(torch.from_numpy(soft), _disc(90, 60)) < _iou(torch.from_numpy(soft), _disc(96, 60))


def test_flicker_is_removed_and_motion_followed_with_the_frames():
    g = torch.Generator().manual_seed(1)
    xs = [60.0 + 4 * t for t in range(10)]
    frames = [_textured(x) for x in xs]
    probs = []
    for x in xs:
        base = _disc(x, 60)
        band = (base - 0.5).abs() < 0.3
        probs.append((base + band * (torch.rand(H, W, generator=g) - 0.5) * 0.3).clamp(0, 1))
    prev, raw, steady = None, [], []
    for t, (p, x) in enumerate(zip(probs, xs, strict=True)):
        res = _result(p, _landmarks(x, 60))
        raw.append(res.mask)
        prev = steady_person(res, prev, 0.15, None if t == 0 else (frames[t - 1], frames[t]))
        steady.append(prev.mask)
    truth = [(_disc(x, 60) > 0.5).float() for x in xs]
    iou_raw = np.mean([_iou(m, tr) for m, tr in zip(raw, truth, strict=True)])
    iou_steady = np.mean([_iou(m, tr) for m, tr in zip(steady, truth, strict=True)])
    assert iou_steady >= iou_raw - 0.01

    def wrong(masks):
        return np.mean([float(((m > 0.5) != (tr > 0.5)).float().mean()) for m, tr in zip(masks, truth, strict=True)])

    assert wrong(steady) < wrong(raw)
