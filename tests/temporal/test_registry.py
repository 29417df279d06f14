import pytest
import torch

from relightnet.checks import InputError
from relightnet.temporal import (
    EMAFilter,
    OneEuroFilter,
    OutlierGate,
    PooledSolve,
    run_causal,
    smooth_lights,
)
from relightnet.temporal.registry import (
    SEQUENCE_SMOOTHING,
    SMOOTHING_METHODS,
    STREAMING_SMOOTHING,
    VIDEO_SMOOTHING,
    PassThrough,
    check_smoothing,
    make_smoother,
    resolve_smoothing,
    smooth_sequence,
    smoothing_names,
)


def _lights(t=24, seed=0):
    g = torch.Generator().manual_seed(seed)
    base = torch.randn(9, 3, generator=g)
    return base + 0.05 * torch.randn(t, 9, 3, generator=g)


def test_every_name_is_listed_once_and_the_job_lists_agree():
    names = tuple(SMOOTHING_METHODS)
    assert len(set(names)) == len(names)
    assert set(VIDEO_SMOOTHING) == {"auto", *names}
    assert set(STREAMING_SMOOTHING) == {"auto", *smoothing_names(causal=True)}
    assert "pooled" not in SEQUENCE_SMOOTHING and "hermite" in SEQUENCE_SMOOTHING
    assert all(SMOOTHING_METHODS[n].offline for n in names)
    assert set(smoothing_names(causal=False)) == {"hermite", "poly", "savgol"}


def test_resolve_auto_and_refusals():
    assert resolve_smoothing("auto", True) == "pooled"
    assert resolve_smoothing("auto", False) == "hermite"
    assert resolve_smoothing("auto", False, causal=True) == "ema"
    with pytest.raises(InputError, match="regresses its light"):
        resolve_smoothing("pooled", False)
    with pytest.raises(InputError, match="offline method"):
        resolve_smoothing("hermite", False, causal=True)
    with pytest.raises(InputError, match="kalman"):
        resolve_smoothing("kalman", False)
    with pytest.raises(InputError, match="--smoothing: expected one of"):
        check_smoothing("hermite", STREAMING_SMOOTHING, "--smoothing")


def test_make_smoother_builds_the_causal_modules():
    assert isinstance(make_smoother("none"), PassThrough)
    assert isinstance(make_smoother("ema", alpha=0.4), EMAFilter) and make_smoother("ema", alpha=0.4).alpha == 0.4
    assert isinstance(make_smoother("one-euro", lmax=1), OneEuroFilter)
    gated = make_smoother("gated-one-euro", persist=3)
    assert isinstance(gated, OutlierGate) and isinstance(gated.filter, OneEuroFilter) and gated.persist == 3
    assert isinstance(make_smoother("pooled", reg=0.1), PooledSolve)
    with pytest.raises(InputError, match="hermite"):
        make_smoother("hermite")
    with pytest.raises(InputError, match="unknown option"):
        make_smoother("ema", beta=1.0)


def test_smooth_sequence_is_the_methods_own_result():
    x = _lights()
    torch.testing.assert_close(smooth_sequence(x, "hermite", knot_spacing=6).smoothed,
                               smooth_lights(x, "hermite", knot_spacing=6).smoothed)
    torch.testing.assert_close(smooth_sequence(x, "ema", alpha=0.5).smoothed, run_causal(EMAFilter(0.5), x))
    torch.testing.assert_close(smooth_sequence(x, "none").smoothed, x)
    assert smooth_sequence(x, "auto").smoothed.shape == x.shape  # hermite without evidence


def test_gated_causal_sequence_flags_a_spike():
    x = _lights(30)
    x[12] += 5.0  # one isolated spike
    res = smooth_sequence(x, "one-euro", gate={"eps": 3.0, "persist": 2})
    assert bool(res.outliers[12]) and int(res.outliers.sum()) <= 2 and not res.switches.any()
    assert smooth_sequence(x, "one-euro").outliers.sum() == 0
