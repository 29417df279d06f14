"""Offline smoothing: noise removal, outliers, switches, batching, gradients, errors."""

import math

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.light import preset_light
from relightnet.sh import rotate_sh_up
from relightnet.temporal import detect_switches, light_distance, light_error, smooth_lights, step_lag
from relightnet.temporal.metrics import outlier_scores
from relightnet.temporal.offline import smooth_hermite, smooth_poly, smooth_savgol

METHOD_OPTS = {
    "hermite": {"knot_spacing": 8},
    "poly": {"degree": 2, "window": 15},
    "savgol": {"window": 15, "degree": 2},
}


def rotating(t_len=120, seed=0, step=None, noise=0.0, dtype=torch.float32):
    """A preset light turning smoothly about the up axis; optionally a switch to another preset at ``step``."""
    a, b = preset_light("studio").to(dtype), preset_light("sunset").to(dtype)
    ang = 0.6 * torch.sin(torch.arange(t_len, dtype=torch.float64) / 25.0)
    truth = torch.stack([rotate_sh_up(a if step is None or t < step else b, float(ang[t])) for t in range(t_len)])
    g = torch.Generator().manual_seed(seed)
    noisy = truth + noise * torch.randn(truth.shape, generator=g, dtype=dtype)
    return truth, noisy


def test_polynomial_data_is_not_flagged_and_kept_exactly(poly_lights):
    x = poly_lights(50, 3)
    res = smooth_poly(x, degree=3, outlier_eps="3mad", switches="auto")
    torch.testing.assert_close(res.smoothed, x, rtol=0, atol=1e-10)
    assert not res.outliers.any() and not res.switches.any()  # rounding errors are not outliers


@pytest.mark.parametrize("method", ["hermite", "poly", "savgol"])
def test_every_method_removes_noise(method):
    truth, noisy = rotating(noise=0.05)
    res = smooth_lights(noisy, method, **METHOD_OPTS[method])
    assert res.smoothed.shape == truth.shape and res.outliers.shape == res.distances.shape == (120,)
    raw, smooth = light_error(noisy, truth).item(), light_error(res.smoothed, truth).item()
    assert smooth < 0.45 * raw, (raw, smooth)


@pytest.mark.parametrize("method", ["hermite", "poly", "savgol"])
def test_injected_outliers_are_detected_and_corrected(method):
    truth, noisy = rotating(t_len=200, noise=0.05, seed=1)
    g = torch.Generator().manual_seed(7)
    idx = torch.randperm(200, generator=g)[:12]
    spikes = torch.randn(12, 9, 3, generator=g)
    spikes *= 5.0 / light_distance(spikes)[:, None, None]  # about a third of the light's norm
    noisy[idx] += spikes
    truth_flags = torch.zeros(200, dtype=torch.bool)
    truth_flags[idx] = True
    res = smooth_lights(noisy, method, outlier_eps="3mad", **METHOD_OPTS[method])
    recall, precision = outlier_scores(res.outliers, truth_flags)
    assert recall >= 0.9 and precision >= 0.7, (recall, precision)
    plain = smooth_lights(noisy, method, **METHOD_OPTS[method]).smoothed
    # Corrected: the spikes no longer leak into the smoothed light.
    err_fixed = light_distance(res.smoothed, truth)[idx].mean()
    err_plain = light_distance(plain, truth)[idx].mean()
    assert err_fixed < 0.4 * err_plain, (err_fixed, err_plain)
    assert light_error(res.smoothed, truth) < 0.35 * light_error(noisy, truth)


def test_noise_level_changing_at_a_switch_does_not_make_outliers():
    # A dim light, then a bright one, each estimated with 5 % noise: thresholds are per segment and local.
    dim, bright = preset_light("night") * 0.2, preset_light("studio") * 3
    truth = torch.stack([dim] * 70 + [bright] * 70)
    g = torch.Generator().manual_seed(11)
    noisy = truth * (1 + 0.05 * torch.randn(truth.shape, generator=g))
    res = smooth_hermite(noisy, outlier_eps="3mad", switches="auto")
    assert res.switches.nonzero().flatten().tolist() == [70]
    assert res.outliers.sum() <= 4
    assert light_error(res.smoothed, truth) < 0.5 * light_error(noisy, truth)


def test_switch_is_detected_and_followed_at_once():
    truth, noisy = rotating(t_len=150, step=80, noise=0.05, seed=2)
    noisy[[20, 79, 81, 120]] += 3.0  # outliers, two of them right at the switch
    sw = detect_switches(noisy)
    assert sw.nonzero().flatten().tolist() == [80]
    split = smooth_hermite(noisy, outlier_eps="3mad", switches="auto")
    assert split.switches.nonzero().flatten().tolist() == [80]
    assert step_lag(split.smoothed, truth, 80) == 0
    assert split.outliers[[20, 79, 81, 120]].all()
    whole = smooth_hermite(noisy, outlier_eps="3mad")
    assert step_lag(whole.smoothed, truth, 80) >= 2  # a spline over the switch blurs it
    assert light_error(split.smoothed, truth) < 0.7 * light_error(whole.smoothed, truth)
    # A smooth sequence without a switch has none.
    _, calm = rotating(t_len=150, noise=0.05, seed=3)
    assert not detect_switches(calm).any()


def test_batched_equals_one_by_one_and_dtype_kept():
    seqs = [rotating(t_len=60, noise=0.05, seed=s, step=30 if s == 1 else None)[1] for s in range(3)]
    batch = torch.stack(seqs)
    res = smooth_lights(batch, "hermite", outlier_eps="3mad", switches="auto", knot_spacing=6)
    assert res.smoothed.shape == (3, 60, 9, 3) and res.outliers.shape == (3, 60)
    assert res.smoothed.dtype == torch.float32
    for i, s in enumerate(seqs):
        one = smooth_lights(s, "hermite", outlier_eps="3mad", switches="auto", knot_spacing=6)
        torch.testing.assert_close(res.smoothed[i], one.smoothed, rtol=1e-5, atol=1e-5)
        assert torch.equal(res.outliers[i], one.outliers) and torch.equal(res.switches[i], one.switches)
    assert res.switches[1].nonzero().flatten().tolist() == [30] and not res.switches[[0, 2]].any()


@pytest.mark.slow
def test_differentiable_in_the_lights():
    _, noisy = rotating(t_len=24, noise=0.05, dtype=torch.float64)
    x = noisy.clone().requires_grad_(True)
    torch.autograd.gradcheck(lambda v: smooth_savgol(v, window=5).smoothed, (x,))
    out = smooth_hermite(x, knot_spacing=6, outlier_eps="3mad").smoothed
    out.square().sum().backward()
    assert torch.isfinite(x.grad).all() and x.grad.abs().sum() > 0


def test_short_sequences_and_single_frames():
    truth, noisy = rotating(t_len=4, noise=0.01)
    for method in ("hermite", "poly", "savgol"):
        res = smooth_lights(noisy, method, outlier_eps="3mad", switches="auto", **METHOD_OPTS[method])
        assert res.smoothed.shape == (4, 9, 3) and torch.isfinite(res.smoothed).all()
    one = smooth_lights(noisy[:1], "hermite")
    torch.testing.assert_close(one.smoothed, noisy[:1])


def test_bad_inputs():
    _, x = rotating(t_len=20)
    with pytest.raises(ShapeError):
        smooth_lights(x[0])  # one light, not a sequence
    with pytest.raises(ShapeError):
        smooth_lights(torch.zeros(20, 8, 3))
    nan = x.clone()
    nan[3, 0, 0] = math.nan
    with pytest.raises(InputError, match="NaN"):
        smooth_lights(nan)
    with pytest.raises(InputError, match="method"):
        smooth_lights(x, "spline")
    with pytest.raises(InputError, match="unknown option"):
        smooth_lights(x, "hermite", window=5)
    with pytest.raises(InputError, match="odd"):
        smooth_savgol(x, window=6)
    with pytest.raises(InputError, match="eps"):
        smooth_lights(x, outlier_eps="3sigma")
    with pytest.raises(InputError, match="knot_spacing"):
        smooth_hermite(x, knot_spacing=0)
    with pytest.raises(ShapeError, match="switches"):
        smooth_lights(x, switches=torch.zeros(5, dtype=torch.bool))


def test_frame_noise_scales_with_the_noise_and_ignores_a_step():
    from relightnet.temporal.offline import frame_noise

    truth, quiet = rotating(t_len=60, step=30, noise=0.02, seed=4)
    _, loud = rotating(t_len=60, step=30, noise=0.08, seed=4)
    q, lo = float(frame_noise(quiet)), float(frame_noise(loud))
    assert 3 < lo / q < 5  # proportional to the noise
    assert float(frame_noise(truth)) < 0.1 * q  # a clean step is not noise
    both = frame_noise(torch.stack([quiet, loud]))
    assert both.shape == (2,) and torch.allclose(both, torch.tensor([q, lo], dtype=both.dtype))
    with pytest.raises(InputError, match="noise"):
        detect_switches(quiet, noise=0.0)
    with pytest.raises(InputError, match="threshold"):
        detect_switches(quiet, eps=None)


def test_noise_rule_finds_steps_not_steady_turns():
    """Without noise a steadily turning light has frame noise 0: the jump profile is flat, no switch."""
    turning = torch.stack([rotate_sh_up(preset_light("studio"), 0.05 * t) for t in range(60)])
    assert not detect_switches(turning, eps=None, noise=8.0).any()
    step, noisy = rotating(t_len=60, step=30, noise=0.02, seed=6)
    assert detect_switches(noisy, eps=None, noise=8.0).nonzero().flatten().tolist() == [30]
    assert detect_switches(step, eps=None, noise=8.0).nonzero().flatten().tolist() == [30]
