"""The causal outlier gate: one step of the test (gate_step) and OutlierGate around a filter."""

import pytest
import torch

from relightnet.checks import InputError
from relightnet.light import preset_light
from relightnet.temporal import EMAFilter, OneEuroFilter, OutlierGate, light_distance, run_causal, step_lag
from relightnet.temporal.gate import gate_step
from relightnet.temporal.metrics import outlier_scores

from .conftest import step_seq


def _state(pred, scale, count):
    """Gate state (1, 3, K, 3): previous output, scale and count slots."""
    ones = torch.ones_like(pred)
    return torch.stack([pred, scale * ones, count * ones])[None]


def test_gate_step_first_frame_passes_and_sets_the_initial_scale():
    light = preset_light("studio")[None].double()
    x_in, first, switch, outlier, scale, count = gate_step(
        3 * light, _state(light[0], 0.7, 1.0), torch.tensor([True]), init=0.05)
    assert torch.equal(x_in, 3 * light) and first.tolist() == [True]
    assert not switch.any() and not outlier.any() and count.tolist() == [0.0]
    assert scale.tolist() == pytest.approx([0.05])  # the scale restarts at init, not updated by the frame


def test_gate_step_small_innovation_updates_the_scale():
    light = preset_light("studio")[None].double()
    x_in, _, switch, outlier, scale, count = gate_step(
        1.01 * light, _state(light[0], 0.05, 0.0), None, eps=3.0, gamma=0.05)
    assert torch.equal(x_in, 1.01 * light) and not switch.any() and not outlier.any() and count.tolist() == [0.0]
    # d = 0.01 (relative to the light's norm) is below 3 × 0.05: the running mean takes it in
    assert scale.tolist() == pytest.approx([0.95 * 0.05 + 0.05 * 0.01])


def test_gate_step_outlier_then_switch():
    light = preset_light("studio")[None].double()
    pred = light[0]
    # A frame twice as bright: d = 1 > 3 × 0.05, the first such frame is an outlier, replaced by the previous output.
    x_in, _, switch, outlier, scale, count = gate_step(2 * light, _state(pred, 0.05, 0.0), None, persist=2)
    assert outlier.tolist() == [True] and not switch.any() and count.tolist() == [1.0]
    assert torch.equal(x_in, light)
    assert scale.tolist() == pytest.approx([0.95 * 0.05 + 0.05 * 0.15])  # the innovation clipped at the threshold
    # The second large frame in a row is a switch: accepted, the count restarts.
    x_in, _, switch, outlier, _, count = gate_step(2 * light, _state(pred, 0.05, 1.0), None, persist=2)
    assert switch.tolist() == [True] and not outlier.any() and count.tolist() == [0.0]
    assert torch.equal(x_in, 2 * light)
    # persist=1: every large frame is a switch at once.
    _, _, switch, outlier, _, _ = gate_step(2 * light, _state(pred, 0.05, 0.0), None, persist=1)
    assert switch.tolist() == [True] and not outlier.any()


def test_outlier_gate_rejects_spikes_and_accepts_switches():
    truth, x = step_seq(t_len=120, step=60, noise=0.05, seed=7)
    spikes = [15, 33, 47, 80, 101]
    x[spikes] += 2.0
    gate = OutlierGate(EMAFilter(0.3), eps=3.0, persist=2)
    y, states = run_causal(gate, x, return_states=True)
    status = states[:, -1, 0, 0]
    flags = status == 1
    true = torch.zeros(120, dtype=torch.bool)
    true[spikes] = True
    recall, precision = outlier_scores(flags, true)
    assert recall == 1.0 and precision >= 0.8
    assert (status == 2).nonzero().flatten().tolist() == [61]  # the switch, accepted on its 2nd frame
    assert step_lag(y, truth, 60) == 1
    plain = run_causal(EMAFilter(0.3), x)
    assert light_distance(y, truth)[spikes].mean() < 0.2 * light_distance(plain, truth)[spikes].mean()


def test_outlier_gate_state_and_parameters():
    gate = OutlierGate(EMAFilter(0.3))
    assert gate.state_size == EMAFilter(0.3).state_size + 4
    for bad in ({"persist": 0}, {"persist": 1.5}, {"persist": True}, {"eps": 0.0}, {"init": -1.0}, {"gamma": 0.0}):
        with pytest.raises(InputError):
            OutlierGate(EMAFilter(), **bad)
    assert run_causal(OutlierGate(OneEuroFilter(lmax=3), lmax=3), torch.ones(5, 16, 3)).shape == (5, 16, 3)
    const = preset_light("studio")[None].expand(6, -1, -1)
    torch.testing.assert_close(run_causal(OutlierGate(EMAFilter(0.3)), const), const)  # a constant light passes
