"""Serving an exported model with ONNX Runtime: OnnxRelighter (streaming state, input checks), int8, run_video."""

import re

import numpy as np
import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.model import normalize_input
from relightnet.model.onnx_serving import INT8_KEEP_FLOAT, OnnxRelighter, calibration_set, quantize_int8, run_video
from relightnet.temporal import make_smoother

from .conftest import make_inputs as _inputs


@pytest.mark.slow
def test_smoothing_layer_in_ort_equals_torch_over_50_frames(exported):
    net, path = exported
    smoother = make_smoother("ema", alpha=0.4)
    r = OnnxRelighter(path)
    state = None
    for t in range(50):
        img, mask = _inputs(1, 32, 32, seed=t)
        out = r.step(img.numpy(), mask.numpy())
        with torch.no_grad():
            raw = net(normalize_input(img, mask)).light
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


def _weight_sources(path):
    """{weight-carrying node's weight input: the op type that makes it, or None for a stored float tensor}."""
    import onnx

    g = onnx.load(str(path)).graph
    made = {o: n.op_type for n in g.node for o in n.output}
    return {n.input[1]: (n.op_type, made.get(n.input[1])) for n in g.node
            if n.op_type in ("Conv", "ConvInteger", "MatMul", "MatMulInteger", "Gemm") and len(n.input) > 1}


def _in_float(op, maker):
    """A float layer: a float op whose weight is a stored tensor (static int8 dequantises its weight;
    dynamic int8 runs ``ConvInteger`` / ``MatMulInteger``)."""
    return op in ("Conv", "Gemm", "MatMul") and maker is None


@pytest.mark.parametrize("mode", ["static", "dynamic"])
def test_keep_float_leaves_the_matching_layers_in_float(exported, tmp_path, mode):
    _, path = exported
    calib = [tuple(t.numpy() for t in _inputs(1, 32, 32, seed=s)) for s in range(2)]
    q = quantize_int8(path, tmp_path / "m_int8.onnx", mode=mode, calibration=calib, keep_float=[r"net\.stem\..*"])
    assert not list(tmp_path.glob(".*"))  # no temporary files left
    src = _weight_sources(q)
    kept = {w for w, (op, maker) in src.items() if _in_float(op, maker)}
    assert kept == {"net.stem.0.weight", "net.stem.3.weight"}  # the stem's two convolutions, in float
    assert len(src) > 4 + len(kept)  # and the other layers in int8
    a, b = OnnxRelighter(path), OnnxRelighter(q)
    img, mask = _inputs(1, 32, 32, seed=9)
    fa, fb = a.step(img.numpy(), mask.numpy()), b.step(img.numpy(), mask.numpy())
    assert np.abs(fa["albedo"] - fb["albedo"]).mean() / np.abs(fa["albedo"]).mean() < 0.1
    everything = _weight_sources(quantize_int8(path, tmp_path / "all.onnx", mode=mode, calibration=calib,
                                               keep_float=()))
    assert not any(_in_float(op, maker) for op, maker in everything.values())
    with pytest.raises(InputError, match="keep_float: not a regular expression"):
        quantize_int8(path, tmp_path / "x.onnx", mode=mode, keep_float=["net.(stem"])
    with pytest.raises(InputError, match="keep_float: expected a sequence"):
        quantize_int8(path, tmp_path / "x.onnx", mode=mode, keep_float="net.stem")
    with pytest.raises(InputError, match="keep_float: expected a sequence"):
        quantize_int8(path, tmp_path / "x.onnx", mode=mode, keep_float=None)
    assert not (tmp_path / "x.onnx").exists()


def test_default_keep_float_names_the_pose_encoders_first_convolutions(exported):
    """The default patterns match the six convolution weights of the shipped model's pose encoder before
    its first residual connection, by the names the export gives them (``net.`` + the torch name)."""
    import onnx

    from relightnet.model import load_model

    _, path = exported
    assert any(i.name == "net.stem.0.weight" for i in onnx.load(str(path)).graph.initializer)
    net = load_model(None)
    tensors = dict(net.named_parameters()) | dict(net.named_buffers())
    hits = {n: t for n, t in tensors.items() if any(re.fullmatch(p, "net." + n) for p in INT8_KEEP_FLOAT)}
    assert sorted(hits) == [f"pose.encoder.params.w{i}" for i in (1, 13, 16, 18, 5, 7)]
    assert all(t.dim() == 4 for t in hits.values())  # convolution weights, not biases


@pytest.mark.slow
def test_calibration_set_draws_generated_people():
    pairs = calibration_set(n=2, size=32)
    assert len(pairs) == 2
    for img, mask in pairs:
        assert img.shape == (1, 3, 32, 32) and img.dtype == np.float32 and 0 <= img.min() and img.max() <= 1
        assert mask.shape == (1, 1, 32, 32) and 0 < mask.mean() < 1
    assert not np.array_equal(pairs[0][0], pairs[1][0])


def test_input_size_and_step_photo(exported):
    net, path = exported
    r = OnnxRelighter(path)
    assert r.input_size == net.config.input_size and (r.state_size, r.n_coeffs) == (1, 9)
    assert r.evidence_outputs == ()
    image = torch.zeros(3, 40, 24)
    mask = torch.zeros(40, 24)
    mask[8:32, 6:18] = 1
    image[:, 8:32, 6:18] = 0.6
    out, box = r.step_photo((image * 255).to(torch.uint8), mask, 32)
    assert out["albedo"].shape == (1, 3, 32, 32) and out["light_raw"].shape == (1, 9, 3)
    assert np.isfinite(out["light_smoothed"]).all()
    assert box is not None
    with pytest.raises(ShapeError):
        r.step_photo(image, mask[:20], 32)


def test_run_video_streams_every_frame(exported, masked_clip, tmp_path):
    from relightnet.io.video import count_frames, video_info
    from relightnet.light import load_light

    _, path = exported
    video, masks = masked_clip(tmp_path, n=4, h=48, w=64)
    res = run_video(path, video, masks, tmp_path / "out", size=32)
    assert res["raw"].shape == (4, 9, 3) and res["smoothed"].shape == (4, 9, 3)
    np.testing.assert_allclose(res["smoothed"][0], res["raw"][0], atol=1e-6)  # the stream starts at frame 0
    np.testing.assert_allclose(load_light(tmp_path / "out" / "lights_raw.npz").numpy(), res["raw"], atol=1e-6)
    np.testing.assert_allclose(load_light(tmp_path / "out" / "lights_smoothed.npz").numpy(), res["smoothed"],
                               atol=1e-6)
    assert count_frames(tmp_path / "out" / "albedo.mp4") == 4
    assert video_info(tmp_path / "out" / "albedo.mp4").size == (48, 64)
    with pytest.raises(InputError, match="multiple of 16"):
        run_video(path, video, masks, tmp_path / "o2", size=20)
    assert not (tmp_path / "o2").exists()


@pytest.mark.slow
def test_int8_of_a_model_that_solves_its_light_opens(tmp_path):
    """A hybrid network's float64 light solve leaves the quantiser shape records of tensors it replaced;
    they are dropped, so the int8 file passes the every-shape-known check and runs (the shipped model is hybrid)."""
    import onnx

    from relightnet.model import NetConfig, RelightNet
    from relightnet.model.onnx_export import export_onnx

    from .conftest import TRAIN_CONFIG

    torch.manual_seed(0)
    net = RelightNet(NetConfig(width=4, max_width=8, levels=2, light_hidden=8, light_mode="hybrid")).eval()
    path = export_onnx(net, tmp_path / "h.onnx", smoothing="pooled", train_config=TRAIN_CONFIG, example_size=32)
    calib = [tuple(t.numpy() for t in _inputs(1, 32, 32, seed=s)) for s in range(2)]
    q = quantize_int8(path, tmp_path / "h_int8.onnx", mode="static", calibration=calib)
    g = onnx.load(str(q)).graph
    made = {o for n in g.node for o in n.output}
    assert all(v.name in made for v in g.value_info)
    img, mask = _inputs(1, 32, 32, seed=3)
    out = OnnxRelighter(q).step(img.numpy(), mask.numpy())
    assert np.isfinite(out["light_smoothed"]).all() and out["albedo"].shape == (1, 3, 32, 32)


@pytest.mark.slow
def test_int8_of_the_shipped_model_relights_within_5_percent_of_fp32(tmp_path):
    """The quality goal for the default int8 file, on 16 generated test people at the model's size:
    relit RMSE (each person relit with the next one's light) within 5% of the fp32 file's (measured: +0.5–0.8%
    on 48 and 64 people; every layer in int8 gave +9–17%). Not an exact value: int8 kernels differ by CPU."""
    from relightnet.body import AnnyBody
    from relightnet.data import SynthConfig, generate_sample
    from relightnet.model import load_model, shading_map
    from relightnet.model.onnx_export import export_onnx

    net = load_model(None)
    fp32 = export_onnx(net, tmp_path / "m.onnx", smoothing="pooled" if net.solves else "ema")
    int8 = quantize_int8(fp32, tmp_path / "m_int8.onnx")
    body, size = AnnyBody(), net.config.input_size
    people = [generate_sample(SynthConfig(res=size, n_dirs=64), "test", i, body=body).arrays for i in range(16)]

    def relit_rmse(path):
        r, errs = OnnxRelighter(path, threads=1), []
        for i, a in enumerate(people):
            light = torch.from_numpy(people[(i + 1) % len(people)]["light"])
            img = np.ascontiguousarray(a["image_srgb"].transpose(2, 0, 1)[None], dtype=np.float32) / 255
            m = a["mask"][None, None].astype(np.float32)
            r.reset()
            out = r.step(img, m)
            pred = torch.from_numpy(out["albedo"]) * shading_map(torch.from_numpy(out["transport"]), light)
            gt = torch.from_numpy(a["albedo"]).permute(2, 0, 1)[None] * shading_map(
                torch.from_numpy(a["transport"]).permute(2, 0, 1)[None], light)
            errs.append(float((((pred - gt) ** 2) * torch.from_numpy(m)).sum() / (m.sum() * 3)) ** 0.5)
        return float(np.mean(errs))

    assert relit_rmse(int8) <= 1.05 * relit_rmse(fp32)
