import numpy as np
import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.model import NetConfig, RelightNet
from relightnet.model.onnx_export import StreamingRelighter, export_onnx, make_smoother
from relightnet.model.onnx_serving import OnnxRelighter, quantize_int8

NET = NetConfig(width=8, max_width=32, light_hidden=32)


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    torch.manual_seed(0)
    net = RelightNet(NET).eval()
    path = tmp_path_factory.mktemp("onnx") / "m.onnx"
    export_onnx(net, path, smoothing="ema", example_size=32, alpha=0.4)
    return net, path


def _inputs(b, h, w, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.rand(b, 3, h, w, generator=g), (torch.rand(b, 1, h, w, generator=g) > 0.3).float()


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


def test_smoothing_layer_in_ort_equals_torch_over_50_frames(exported):
    net, path = exported
    smoother = make_smoother("ema", alpha=0.4)
    r = OnnxRelighter(path)
    state = None
    for t in range(50):
        img, mask = _inputs(1, 32, 32, seed=t)
        out = r.step(img.numpy(), mask.numpy())
        with torch.no_grad():
            raw = net(__import__("relightnet.model", fromlist=["normalize_input"]).normalize_input(img, mask)).light
            y, state = smoother(raw, state if state is not None else torch.zeros(1, 1, 9, 3),
                                torch.tensor([t == 0]))
        assert np.abs(out["light_smoothed"] - y.numpy()).max() <= 1e-4
    r.reset()
    img, mask = _inputs(1, 32, 32, seed=0)
    first = r.step(img.numpy(), mask.numpy())
    np.testing.assert_allclose(first["light_smoothed"], first["light_raw"], atol=1e-6)


def test_bad_inputs_and_files(exported, tmp_path):
    _, path = exported
    r = OnnxRelighter(path)
    img, mask = _inputs(1, 32, 32)
    with pytest.raises(InputError, match="expected exactly"):
        r.run({"img": img.numpy()})
    with pytest.raises(InputError, match="float32"):
        r.step(img.double().numpy(), mask.numpy())
    with pytest.raises(ShapeError, match="multiples of 16"):
        r.step(np.zeros((1, 3, 30, 32), np.float32), np.zeros((1, 1, 30, 32), np.float32))
    with pytest.raises(ShapeError, match="mask: expected"):
        r.step(img.numpy(), np.zeros((1, 1, 16, 16), np.float32))
    bad = tmp_path / "trunc.onnx"
    bad.write_bytes(path.read_bytes()[:5000])
    with pytest.raises(InputError, match="unreadable ONNX model"):
        OnnxRelighter(bad)
    with pytest.raises(InputError, match="not found"):
        OnnxRelighter(tmp_path / "none.onnx")


@pytest.mark.parametrize("mode", ["static", "dynamic"])
def test_int8_model_runs_close_to_fp32(exported, tmp_path, mode):
    import onnx

    _, path = exported
    calib = [tuple(t.numpy() for t in _inputs(1, 32, 32, seed=s)) for s in range(4)]
    q = quantize_int8(path, tmp_path / "m_int8.onnx", mode=mode, calibration=calib)
    assert q.stat().st_size < path.stat().st_size
    assert not list(tmp_path.glob(".*"))  # no temporary files left
    ops = {n.op_type for n in onnx.load(str(q)).graph.node}
    assert ("QuantizeLinear" in ops) if mode == "static" else ("DynamicQuantizeLinear" in ops or "MatMulInteger" in ops
                                                                 or "ConvInteger" in ops)
    a, b = OnnxRelighter(path), OnnxRelighter(q)
    img, mask = _inputs(1, 32, 32, seed=9)
    fa, fb = a.step(img.numpy(), mask.numpy()), b.step(img.numpy(), mask.numpy())
    rel = np.abs(fa["albedo"] - fb["albedo"]).mean() / np.abs(fa["albedo"]).mean()
    assert rel < 0.1
    with pytest.raises(InputError, match="mode"):
        quantize_int8(path, tmp_path / "x.onnx", mode="int4")


def test_calibration_set_draws_generated_people():
    from relightnet.model.onnx_serving import calibration_set

    pairs = calibration_set(n=2, size=32)
    assert len(pairs) == 2
    for img, mask in pairs:
        assert img.shape == (1, 3, 32, 32) and img.dtype == np.float32 and 0 <= img.min() and img.max() <= 1
        assert mask.shape == (1, 1, 32, 32) and 0 < mask.mean() < 1
    assert not np.array_equal(pairs[0][0], pairs[1][0])


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
