"""Causal filters: EMA theory, one-euro trade-off, loop-free forms, is_first resets, ONNX (gate: test_gate.py)."""

import math

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.light import preset_light
from relightnet.temporal import EMAFilter, FIRFilter, OneEuroFilter, OutlierGate, jitter, run_causal, step_lag
from relightnet.temporal.causal import ema_matrix, ema_sequence, fir_sequence, fir_taps

from .conftest import step_seq


def all_filters():
    return [EMAFilter(0.3), OneEuroFilter(0.5, 1.0), FIRFilter(5), FIRFilter(6, 1), OutlierGate(OneEuroFilter()),
            OutlierGate(FIRFilter(4))]


@pytest.mark.parametrize("alpha", [0.1, 0.3, 0.75])
def test_ema_step_response_and_lag_follow_theory(alpha):
    truth, x = step_seq()
    y = run_causal(EMAFilter(alpha), x)
    a, b = truth[0], truth[-1]
    n = torch.arange(30, dtype=torch.float64)
    expected = a + (1 - (1 - alpha) ** (n + 1))[:, None, None].float() * (b - a)
    torch.testing.assert_close(y[10:], expected, rtol=1e-5, atol=1e-5)
    torch.testing.assert_close(y[:10], truth[:10])  # y_0 = x_0, constants pass
    lag = math.ceil(math.log(0.1) / math.log(1 - alpha)) - 1  # first n with 1 - (1-α)^(n+1) >= 0.9
    assert step_lag(y, truth, 10).item() == lag


def test_one_euro_smooths_slow_signals_and_follows_fast_ones():
    # Slow: a constant light with noise. The one-euro filter must cut the jitter like a heavy EMA.
    _, noisy = step_seq(t_len=200, step=199, noise=0.05, seed=1)
    calm = noisy[:190]
    euro = OneEuroFilter(min_cutoff=0.5, beta=2.0, rate=30)
    j_raw, j_euro = jitter(calm), jitter(run_causal(euro, calm)[20:])
    assert j_euro < 0.2 * j_raw, (j_raw, j_euro)
    # Fast: a switch. The one-euro filter follows within 2 frames; an EMA at its resting cutoff takes > 5.
    truth, x = step_seq(noise=0.05, seed=2)
    slow_alpha = 1 / (1 + 30 / (2 * math.pi * 0.5))
    assert step_lag(run_causal(euro, x), truth, 10) <= 2
    assert step_lag(run_causal(EMAFilter(slow_alpha), x), truth, 10) > 5


def test_loop_free_forms_equal_the_stepwise_filters():
    _, x = step_seq(t_len=33, noise=0.1)
    batch = torch.stack([x, x.flip(0)])  # (2, T, K, 3)
    for alpha in (0.2, 1.0):
        torch.testing.assert_close(ema_sequence(batch, alpha), run_causal(EMAFilter(alpha), batch))
    M = ema_matrix(6, 0.5, torch.float64)
    assert torch.equal(M, M.tril()) and torch.allclose(M.sum(1), torch.ones(6, dtype=torch.float64))
    for window, degree in [(5, 0), (7, 1), (4, 2)]:
        taps = fir_taps(window, degree)
        torch.testing.assert_close(fir_sequence(batch, taps), run_causal(FIRFilter(taps=taps), batch))
        torch.testing.assert_close(fir_sequence(x, taps), run_causal(FIRFilter(window, degree), x))


def test_fir_taps():
    torch.testing.assert_close(fir_taps(4), torch.full((4,), 0.25))
    torch.testing.assert_close(fir_taps(5, 1), torch.tensor([3.0, 2.0, 1.0, 0.0, -1.0]) / 5)
    # Degree 1 follows a ramp without lag once the window is full.
    ramp = torch.arange(20.0)[:, None, None] * preset_light("night")
    torch.testing.assert_close(fir_sequence(ramp, fir_taps(5, 1))[4:], ramp[4:], rtol=1e-5, atol=1e-4)


@pytest.mark.parametrize("filt", all_filters(), ids=lambda f: type(f).__name__)
def test_is_first_resets_the_state(filt):
    _, a = step_seq(t_len=15, noise=0.1, seed=3)
    _, b = step_seq(t_len=12, step=4, noise=0.1, seed=4)
    ya, yb = run_causal(filt, a), run_causal(filt, b)
    # One stream through both sequences, is_first raised on b's first frame; batch of 2 where
    # only item 1 restarts mid-way.
    both = torch.cat([a, b])
    state = filt.init_state(both[:1])
    outs = []
    for t in range(both.shape[0]):
        first = torch.tensor([[t in (0, 15)]])  # (B, 1) form
        y, state = filt(both[t : t + 1], state, first)
        assert y.shape == (1, 9, 3) and state.shape == (1, filt.state_size, 9, 3)
        outs.append(y[0])
    out = torch.stack(outs)
    torch.testing.assert_close(out[:15], ya)
    torch.testing.assert_close(out[15:], yb)
    # state=None starts a sequence too.
    y0, _ = filt(a[:2])
    torch.testing.assert_close(y0[0], ya[0])


def test_batches_are_independent():
    _, a = step_seq(t_len=20, noise=0.1, seed=5)
    _, b = step_seq(t_len=20, step=7, noise=0.1, seed=6)
    for filt in all_filters():
        yab = run_causal(filt, torch.stack([a, b]))
        assert yab.shape == (2, 20, 9, 3)
        torch.testing.assert_close(yab[0], run_causal(filt, a))
        torch.testing.assert_close(yab[1], run_causal(filt, b))


@pytest.mark.slow
def test_forward_exports_as_one_graph():
    # torch.export refuses data-dependent Python control flow and records no frame loop: the
    # exported step, fed its own state, must equal the eager filter (is_first flips in the run).
    _, x = step_seq(t_len=12, noise=0.1)
    for filt in all_filters():
        args = (x[:1], filt.init_state(x[:1]), torch.tensor([True]))
        step = torch.export.export(filt, args).module()
        ref_state = exp_state = filt.init_state(x[:1])
        for t in range(12):
            first = torch.tensor([t in (0, 7)])
            y_ref, ref_state = filt(x[t : t + 1], ref_state, first)
            y_exp, exp_state = step(x[t : t + 1], exp_state, first)
            torch.testing.assert_close(y_exp, y_ref)


@pytest.mark.filterwarnings("ignore")
@pytest.mark.slow
def test_onnx_export_runs_a_stream_in_onnxruntime():
    """The streaming contract: one step exported (dynamic batch), the state fed back by the caller."""
    import numpy as np
    import onnxruntime as ort

    filt = OutlierGate(OneEuroFilter(0.5, 1.0))
    x0 = preset_light("studio")[None].repeat(2, 1, 1)
    batch = torch.export.Dim("B")
    prog = torch.onnx.export(
        filt, (x0, filt.init_state(x0), torch.tensor([True, False])), dynamo=True,
        input_names=["x", "state", "is_first"], output_names=["y", "new_state"],
        dynamic_shapes=({0: batch}, {0: batch}, {0: batch}),
    )
    sess = ort.InferenceSession(prog.model_proto.SerializeToString(), providers=["CPUExecutionProvider"])
    _, a = step_seq(t_len=24, step=12, noise=0.05, seed=8)
    a[5] += 2.0  # an outlier for the gate
    seq = torch.stack([a, a.flip(0), a.roll(3, 0)])  # B = 3, not the export's 2
    state = filt.init_state(seq[:, 0]).numpy()
    outs = []
    for t in range(24):
        first = np.array([t == 0, t == 0, t in (0, 10)])  # item 2 restarts at frame 10
        y, state = sess.run(None, {"x": seq[:, t].numpy(), "state": state, "is_first": first})
        outs.append(y)
    got = torch.from_numpy(np.stack(outs, 1))
    ref = run_causal(filt, seq[:2])
    torch.testing.assert_close(got[:2], ref, rtol=1e-5, atol=1e-5)
    torch.testing.assert_close(got[2, 10:], run_causal(filt, seq[2, 10:]), rtol=1e-5, atol=1e-5)


def test_bad_parameters():
    with pytest.raises(InputError):
        EMAFilter(0.0)
    with pytest.raises(InputError):
        EMAFilter(1.5)
    with pytest.raises(InputError):
        OneEuroFilter(min_cutoff=-1)
    with pytest.raises(InputError):
        OneEuroFilter(beta=-1)
    with pytest.raises(InputError):
        fir_taps(3, 3)
    with pytest.raises(ShapeError):
        FIRFilter(taps=torch.ones(1))
    with pytest.raises(ShapeError):
        run_causal(EMAFilter(), torch.zeros(5, 8, 3))
    with pytest.raises(ShapeError, match="lmax"):
        run_causal(OneEuroFilter(), torch.ones(5, 16, 3))  # built for lmax 2
