import pytest
import torch

from relightnet.checks import InputError
from relightnet.light import preset_light
from relightnet.names import SEQUENCE_SMOOTHING, SMOOTHING_METHODS, STREAMING_SMOOTHING, VIDEO_SMOOTHING
from relightnet.temporal import (
    EMAFilter,
    OneEuroFilter,
    OutlierGate,
    PooledSolve,
    run_causal,
    smooth_lights,
)
from relightnet.temporal.registry import (
    PassThrough,
    check_smoothing,
    make_smoother,
    resolve_smoothing,
    smooth_sequence,
    smooth_video_lights,
)


def _lights(t=24, seed=0):
    g = torch.Generator().manual_seed(seed)
    base = torch.randn(9, 3, generator=g)
    return base + 0.05 * torch.randn(t, 9, 3, generator=g)


def test_every_method_of_the_table_is_implemented_with_its_options():
    x = _lights(8)
    assert "pooled" not in SEQUENCE_SMOOTHING and "hermite" in SEQUENCE_SMOOTHING
    assert set(VIDEO_SMOOTHING) == {"auto", *SMOOTHING_METHODS}
    for name, m in SMOOTHING_METHODS.items():
        if m.causal:
            make_smoother(name)
        if not m.evidence:
            assert smooth_sequence(x, name).smoothed.shape == x.shape
        if m.options and not m.evidence:  # an option not in the table is refused, naming the ones it takes
            with pytest.raises(InputError, match=m.options[0]):
                smooth_sequence(x, name, no_such_option=1)


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
    assert resolve_smoothing("hermite", False, frames=3) == "hermite"
    assert resolve_smoothing("ema", False, frames=1) == "ema"  # a filter runs on any length


def test_a_short_clip_falls_back_to_none_with_a_warning(caplog):
    with caplog.at_level("WARNING", logger="relightnet.temporal"):
        assert resolve_smoothing("auto", False, frames=2) == "none"
    assert "too few to fit" in caplog.text


def test_smoothing_none_and_short_clips():
    raw = torch.randn(5, 9, 3)
    sm, out, sw, used = smooth_video_lights(raw, "none")
    assert torch.equal(sm, raw) and not out.any() and not sw.any()
    sm, _, _, used = smooth_video_lights(raw[:2], "hermite")  # too short to fit: the raw lights, reported
    assert torch.equal(sm, raw[:2]) and used == "none"
    assert smooth_video_lights(raw, "auto").method == "hermite"


def test_robust_smoothing_replaces_a_spike():
    L = preset_light("studio")
    raw = L[None].repeat(12, 1, 1)
    raw[5] = 3 * L  # one bad frame
    sm, out, sw, _ = smooth_video_lights(raw, "hermite")
    assert out.tolist() == [t == 5 for t in range(12)] and not sw.any()
    torch.testing.assert_close(sm[5], L, atol=1e-3, rtol=1e-3)
    with pytest.raises(InputError):
        smooth_video_lights(raw, "no-such-method")


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
