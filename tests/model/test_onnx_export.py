"""ONNX export: the graph equals the torch model and its smoother frame by frame; metadata; refusals."""

import hashlib
import json

import numpy as np
import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.model import NetConfig, RelightNet
from relightnet.model.onnx_export import StreamingRelighter, export_onnx
from relightnet.model.onnx_serving import OnnxRelighter
from relightnet.names import STREAMING_SMOOTHING
from relightnet.temporal import make_smoother

from .conftest import NET, TRAIN_CONFIG
from .conftest import make_inputs as _inputs


def test_ort_matches_torch_at_several_sizes_and_batches(exported):
    net, path = exported
    ref = StreamingRelighter(net, make_smoother("ema", alpha=0.4)).eval()
    r = OnnxRelighter(path)
    assert r.metadata["relightnet.sh_order"] == "2" and r.metadata["relightnet.smoothing"] == "ema"
    for b, h, w in ((1, 32, 32), (3, 48, 64), (2, 96, 32)):
        img, mask = _inputs(b, h, w)
        state = torch.randn(b, 1, 9, 3)
        first = torch.tensor([True] + [False] * (b - 1))
        outs = r.run({"image": img.numpy(), "mask": mask.numpy(), "light_state": state.numpy(),
                      "is_first": first.numpy()})
        with torch.no_grad():
            expected = ref(img, mask, state, first)
        for o, e in zip(outs, expected, strict=True):
            assert np.abs(o - e.numpy()).max() <= 1e-4


@pytest.mark.slow
def test_pooled_solve_in_the_graph_equals_torch_over_12_frames(tmp_path):
    """A hybrid network exported with the 'pooled' smoother: evidence outputs and the pooled light match torch
    frame by frame, and the predictor hands the evidence to the video jobs."""
    from relightnet.pipeline.backends import OnnxPredictor

    torch.manual_seed(1)
    net = RelightNet(NetConfig(width=8, max_width=32, light_hidden=32, light_mode="hybrid")).eval()
    path = export_onnx(net, tmp_path / "p.onnx", smoothing="pooled", example_size=32)
    r = OnnxRelighter(path)
    assert r.evidence_outputs == ("evidence_M", "evidence_r", "light_prior")
    assert r.metadata["relightnet.light_mode"] == "hybrid"
    ref = StreamingRelighter(net, make_smoother("pooled", reg=net.config.solve_reg)).eval()
    state = torch.zeros(1, ref.smoother.state_size, 9, 3)
    for t in range(12):
        img, mask = _inputs(1, 32, 32, seed=t % 3)  # three "poses" under one light
        out = r.step(img.numpy(), mask.numpy())
        with torch.no_grad():
            exp = ref(img, mask, state, torch.tensor([t == 0]))
        state = exp[4]
        for name, e in zip(("light_raw", "light_smoothed", "evidence_M", "evidence_r", "light_prior"),
                           (exp[2], exp[3], exp[5], exp[6], exp[7]), strict=True):
            np.testing.assert_allclose(out[name], e.numpy(), rtol=1e-3, atol=1e-4)
    light, ev, prior = OnnxPredictor(path).light_evidence(img[0], mask[0, 0])
    assert ev is not None and prior is not None and light.shape == (9, 3)
    with pytest.raises(InputError, match="pooled"):
        export_onnx(RelightNet(NET).eval(), tmp_path / "h.onnx", smoothing="pooled")


def test_metadata_describes_the_graph(exported):
    import onnx

    net, path = exported
    meta = {p.key: p.value for p in onnx.load(str(path)).metadata_props}
    assert meta["relightnet.smoothing"] == "ema" and meta["relightnet.state_size"] == "1"
    assert meta["relightnet.light_mode"] == net.config.light_mode
    assert meta["relightnet.input_size"] == str(net.config.input_size)
    digest = hashlib.sha256(json.dumps(TRAIN_CONFIG, sort_keys=True).encode()).hexdigest()
    assert meta["relightnet.train_config_sha256"] == digest
    graph = onnx.load(str(path)).graph
    assert [i.name for i in graph.input] == ["image", "mask", "light_state", "is_first"]
    assert [o.name for o in graph.output] == ["albedo", "transport", "light_raw", "light_smoothed", "light_state_out"]


def test_bad_exports_write_nothing(tmp_path):
    net = RelightNet(NET).eval()
    with pytest.raises(InputError, match="expected an .onnx output file"):
        export_onnx(net, tmp_path / "m.txt")
    with pytest.raises(InputError, match="example_size: expected a multiple of 16, got 20"):
        export_onnx(net, tmp_path / "m.onnx", example_size=20)
    with pytest.raises(InputError):
        export_onnx(net, tmp_path / "m.onnx", smoothing="no-such-smoother")
    assert list(tmp_path.iterdir()) == []
    assert "ema" in STREAMING_SMOOTHING and "pooled" in STREAMING_SMOOTHING


@pytest.mark.slow
def test_pose_encoder_and_cone_head_export_into_one_graph(tmp_path):
    cfg = NetConfig(width=8, max_width=32, light_hidden=32, light_mode="hybrid", transport_head="cone",
                    encoder="pose", input_size=32)
    torch.manual_seed(0)
    net = RelightNet(cfg).eval()
    with torch.no_grad():
        for p in net.pose.proj.parameters():
            p.normal_(0, 0.1)
    path = export_onnx(net, tmp_path / "m.onnx", smoothing="ema")
    assert len(list(tmp_path.iterdir())) == 1  # one file: the pose encoder's weights are inside
    ref = StreamingRelighter(net, make_smoother("ema")).eval()
    img, mask = _inputs(2, 64, 32)
    state, first = torch.zeros(2, 1, 9, 3), torch.tensor([True, True])
    outs = OnnxRelighter(path).run({"image": img.numpy(), "mask": mask.numpy(), "light_state": state.numpy(),
                                    "is_first": first.numpy()})
    with torch.no_grad():
        expected = ref(img, mask, state, first)
    for o, e in zip(outs, expected, strict=True):
        scale = max(1.0, float(e.abs().max()))
        assert np.abs(o - e.numpy()).max() <= 1e-4 * scale


@pytest.mark.slow
def test_half_resolution_network_exports_and_ort_agrees(tmp_path):
    """work_scale 2 (pose encoder, cone head, hybrid solve, guided upsampling) in one graph, at multiples of 32.
    Float32 rounding (2⁻²⁴ ≈ 6e-8 per operation) over a few hundred dependent operations: 1e-4 of the
    output's scale bounds the difference between ONNX Runtime's and torch's kernels."""
    cfg = NetConfig(width=8, max_width=32, light_hidden=32, light_mode="hybrid", transport_head="cone",
                    encoder="pose", input_size=64, work_scale=2)
    torch.manual_seed(0)
    net = RelightNet(cfg).eval()
    with torch.no_grad():
        for p in net.pose.proj.parameters():
            p.normal_(0, 0.1)
    with pytest.raises(InputError, match="multiple of 32"):
        export_onnx(net, tmp_path / "bad.onnx", example_size=48)
    path = export_onnx(net, tmp_path / "m.onnx", smoothing="ema")
    r = OnnxRelighter(path)
    assert "multiples of 32" in r.metadata["relightnet.input"] and r.multiple == 32
    with pytest.raises(ShapeError, match="multiples of 32"):  # a one-line error, not one from inside the graph
        r.step(*(a.numpy() for a in _inputs(1, 48, 48)))
    from relightnet.pipeline.backends import OnnxPredictor

    with pytest.raises(InputError, match="multiple of 32"):
        OnnxPredictor(path, size=48)
    ref = StreamingRelighter(net, make_smoother("ema")).eval()
    for b, h, w in ((2, 64, 32), (1, 32, 96)):
        img, mask = _inputs(b, h, w)
        state, first = torch.zeros(b, 1, 9, 3), torch.ones(b, dtype=torch.bool)
        outs = r.run({"image": img.numpy(), "mask": mask.numpy(), "light_state": state.numpy(),
                      "is_first": first.numpy()})
        with torch.no_grad():
            expected = ref(img, mask, state, first)
        for o, e in zip(outs, expected, strict=True):
            assert o.shape == tuple(e.shape)
            assert np.abs(o - e.numpy()).max() <= 1e-4 * max(1.0, float(e.abs().max()))
