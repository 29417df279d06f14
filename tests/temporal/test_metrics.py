"""Metrics: jitter, error to truth, step lag, outlier recall/precision."""

import math

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.light import preset_light
from relightnet.temporal import jitter, light_distance, light_error, step_lag
from relightnet.temporal.distance import light_norm
from relightnet.temporal.metrics import outlier_scores


def test_jitter_zero_on_ramps_and_exact_on_a_single_kick():
    a, b = preset_light("studio"), preset_light("sunset")
    t = torch.arange(10.0)[:, None, None]
    ramp = a + t * (b - a) / 9
    assert jitter(ramp).item() == pytest.approx(0, abs=1e-5)
    kick = torch.stack([a] * 7)
    kick[3] = b  # second differences at t = 2, 3, 4: (b−a), −2(b−a), (b−a)
    d = light_distance(a, b).item()
    assert jitter(kick).item() == pytest.approx(4 * d / 5, rel=1e-5)
    assert jitter(kick, space="coeff").item() == pytest.approx(4 * (b - a).abs().mean().item() / 5, rel=1e-5)
    mask = torch.ones(7, dtype=torch.bool)
    mask[2:5] = False
    assert jitter(kick, mask=mask).item() == pytest.approx(0, abs=1e-6)
    assert jitter(torch.stack([kick, ramp[:7]])).shape == (2,)


def test_light_error_absolute_and_relative():
    a = preset_light("night")
    seq = torch.stack([a] * 4)
    est = seq * 1.1
    assert light_error(est, seq).item() == pytest.approx(0.1 * light_norm(a).item(), rel=1e-5)
    assert light_error(est, seq, relative=True).item() == pytest.approx(0.1, rel=1e-5)
    with pytest.raises(ShapeError):
        light_error(est[:3], seq)


def test_step_lag_counts_frames_to_90_percent():
    a, b = preset_light("studio"), preset_light("sunset")
    truth = torch.stack([a] * 5 + [b] * 10)
    assert step_lag(truth, truth, 5).item() == 0
    late = torch.stack([a] * 8 + [b] * 7)  # three frames late
    assert step_lag(late, truth, 5).item() == 3
    frac = torch.tensor([0.0] * 5 + [0.5, 0.85, 0.95] + [1.0] * 7)[:, None, None]
    ramp = a + frac * (b - a)
    assert step_lag(ramp, truth, 5).item() == 2
    assert step_lag(ramp, truth, 5, level=0.5).item() == 0
    assert math.isinf(step_lag(torch.stack([a] * 15), truth, 5).item())
    with pytest.raises(InputError, match="no jump"):
        step_lag(truth, truth, 3)
    with pytest.raises(InputError):
        step_lag(truth, truth, 0)


def test_outlier_scores():
    true = torch.tensor([0, 1, 1, 0, 1, 0], dtype=torch.bool)
    pred = torch.tensor([0, 1, 0, 1, 1, 0], dtype=torch.bool)
    assert outlier_scores(pred, true) == (2 / 3, 2 / 3)
    assert outlier_scores(torch.zeros(6, dtype=torch.bool), true) == (0.0, 1.0)
    assert outlier_scores(pred, torch.zeros(6, dtype=torch.bool)) == (1.0, 0.0)
    with pytest.raises(ShapeError):
        outlier_scores(pred[:3], true)


def test_bad_inputs():
    with pytest.raises(ShapeError):
        jitter(torch.zeros(2, 9, 3))
    with pytest.raises(InputError):
        jitter(torch.zeros(5, 9, 3), space="rgb")
    with pytest.raises(ShapeError):
        jitter(torch.zeros(5, 9, 3), mask=torch.ones(4, dtype=torch.bool))


def test_light_drift_is_the_distance_from_the_mean_over_its_level():
    from relightnet.temporal import light_drift

    L = torch.zeros(9, 3)
    L[0] = 1.0
    const = L.expand(5, 9, 3)
    assert torch.equal(light_drift(const), torch.zeros(5))
    swing = torch.stack([L * 0.9, L * 1.1])  # ±10% of the level
    torch.testing.assert_close(light_drift(swing), torch.full((2,), 0.1))
    assert float(light_norm(L)) > 0
