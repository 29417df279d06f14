"""The shipped pose model's graph run by torch (GraphModule) against ONNX Runtime running the file itself.

Tolerance. Both engines compute the same float32 graph with different summation orders (ONNX
Runtime: blocked NCHWc convolutions with fused activations), so they differ by about float32's own
rounding error of this computation, not by zero. That error grows with depth and with the weights'
gain. Measured against a float64 run of the same module: the trunk's taps and the landmark outputs
are off by <= 5e-5 of their scale (max |value|; unit roundoff 6e-8, ~50 layers of sums over up to
864 * 25 terms), the mask logits by 1e-4 to 2e-4 (the last 256² convolutions have a gain of ~300:
logits of +-1600 from inputs <= 6), and ONNX Runtime's own float32 error is up to 3.5x torch's. So
each tensor is compared at ``max(1e-4 * scale, 8 * |float32 - float64|)``: 8x torch's measured
float32 error of that very tensor (2x margin over ONNX Runtime's), never tighter than 1e-4 of the
scale. A wrong op (the first pad on the far side, a resize with aligned corners) is off by 0.2 to
1 of the scale. The presence output is a probability near 0 (a sigmoid of about -11 on these
inputs; ONNX Runtime's sigmoid is a fast approximation there), compared to 1e-6 absolute.
"""

import numpy as np
import pytest
import torch
from torch import nn

from relightnet.checks import InputError, ShapeError
from relightnet.model.onnx_torch import (
    POSE_TAPS,
    GraphModule,
    cut_to_outputs,
    find_stride_taps,
    load_onnx,
    pose_encoder,
)

onnx = pytest.importorskip("onnx")
ort = pytest.importorskip("onnxruntime")

TAPS = [t.name for t in POSE_TAPS]
OUTPUTS = ["Identity", "Identity_1", "Identity_2", "Identity_3", "Identity_4"]


@pytest.fixture(scope="module")
def pose():
    return load_onnx()


def _session(model, outputs, dynamic=False):
    """An ONNX Runtime session of ``model`` returning ``outputs`` (intermediate tensors made outputs)."""
    m = onnx.ModelProto.FromString(model.SerializeToString())  # load_onnx's message, as onnx's own
    if dynamic:
        for dim, name in zip(m.graph.input[0].type.tensor_type.shape.dim, ("B", "H", "W"), strict=False):
            dim.dim_param = name
    cut_to_outputs(m, outputs)
    opts = ort.SessionOptions()
    opts.intra_op_num_threads, opts.log_severity_level = 1, 3
    return ort.InferenceSession(m.SerializeToString(), opts, providers=["CPUExecutionProvider"])


def _image(b, size, seed=0):
    """(B, 3, size, size) in [0, 1]: smooth colour fields with noise, something like a photo."""
    g = torch.Generator().manual_seed(seed)
    low = torch.rand(b, 3, size // 16, size // 16, generator=g)
    smooth = nn.functional.interpolate(low, size=(size, size), mode="bilinear", align_corners=False)
    return (0.8 * smooth + 0.2 * torch.rand(b, 3, size, size, generator=g)).clamp(0, 1)


def _compare(model, names, x):
    ref = _session(model, names, dynamic=x.shape[0] != 1 or x.shape[2] != 256).run(
        names, {"input_1": x.permute(0, 2, 3, 1).numpy()})
    net = GraphModule(model, names)
    with torch.no_grad():
        got = [y.numpy() for y in net(x)]
        got64 = [y.numpy() for y in net.double()(x.double())]
    for name, r, y, y64 in zip(names, ref, got, got64, strict=True):
        assert y.shape == r.shape, name
        err = np.abs(y - r).max()
        if name == "Identity_1":
            assert err <= 1e-6, name
            continue
        scale = np.abs(y64).max()
        tol = max(1e-4 * scale, 8 * np.abs(y - y64).max())
        assert err <= tol, f"{name}: |torch - ort| {err:.3g} > {tol:.3g} (scale {scale:.3g})"


def test_every_output_and_tap_matches_onnxruntime(pose):
    _compare(pose, OUTPUTS + TAPS, _image(1, 256))


def test_a_batch_of_two_matches_onnxruntime(pose):
    # Identity_2's Reshape is fixed to (1, 256, 256, 1) in the file; the others reshape to (-1, n)
    _compare(pose, ["Identity", "Identity_3", "Identity_4"] + TAPS, _image(2, 256, seed=1))


def test_taps_at_another_size_match_onnxruntime(pose):
    _compare(pose, TAPS, _image(2, 128, seed=2))


def test_pose_taps_are_the_last_activation_at_each_trunk_stride(pose):
    assert find_stride_taps(pose) == POSE_TAPS
    enc = pose_encoder()
    with torch.no_grad():
        for size in (128, 512):
            maps = enc(torch.zeros(1, 3, size, size))
            assert [tuple(m.shape) for m in maps] == [(1, t.channels, size // t.stride, size // t.stride)
                                                      for t in POSE_TAPS]


def test_the_encoder_builds_only_the_trunk(pose):
    enc, full = pose_encoder(), GraphModule(pose, OUTPUTS)
    n_enc, n_full = (sum(p.numel() for p in m.parameters()) for m in (enc, full))
    assert n_enc < 0.5 * n_full  # the heads (regression, mask and heatmap decoders) are not built
    assert "t106_0" not in enc._node_params and "t105_0" in enc._node_params


def test_a_fixed_reshape_refuses_another_batch_and_a_channels_last_image_is_refused(pose):
    net = GraphModule(pose, ["Identity_2"])
    with pytest.raises(ShapeError, match="Reshape"), torch.no_grad():
        net(torch.zeros(2, 3, 256, 256))
    with pytest.raises(ShapeError, match=r"x: expected \(B, 3, H, W\)"), torch.no_grad():
        pose_encoder()(torch.zeros(1, 256, 256, 3))


def test_frozen_by_default_and_thawed_after_a_stride():
    enc = pose_encoder()
    assert not any(p.requires_grad for p in enc.parameters())
    enc = pose_encoder(train_after=16)
    x = _image(1, 64)
    maps = enc(x)
    sum(m.square().mean() for m in maps).backward()
    thawed = {name for name, p in enc.named_parameters() if p.requires_grad}
    assert thawed and len(thawed) < len(list(enc.parameters()))
    for out in ("t81_0", "t104_0"):  # the stride-32 stage
        assert all(p.requires_grad and p.grad is not None and p.grad.abs().sum() > 0
                   for p in enc.node_parameters(out))
    for out in ("t2_0", "t78_0"):  # up to the stride-16 tap
        assert all(not p.requires_grad and p.grad is None for p in enc.node_parameters(out))
    enc.set_trainable()
    assert all(p.requires_grad for p in enc.parameters())
    w, b = enc.node_parameters("t2_0")
    assert w.shape == (24, 3, 3, 3) and b.shape == (24,)


def _tiny(op="Softmax", **attrs):
    """A graph input (1, 4, 4, 3) -> Transpose to NCHW -> Conv 3 -> 2 -> ``op`` -> y."""
    h = onnx.helper
    w = onnx.numpy_helper.from_array(np.ones((2, 3, 1, 1), np.float32), "w")
    nodes = [h.make_node("Transpose", ["x"], ["t"], perm=[0, 3, 1, 2]),
             h.make_node("Conv", ["t", "w"], ["c"], kernel_shape=[1, 1]),
             h.make_node(op, ["c"], ["y"], **attrs)]
    graph = h.make_graph(nodes, "tiny", [h.make_tensor_value_info("x", onnx.TensorProto.FLOAT, [1, 4, 4, 3])],
                         [h.make_tensor_value_info("y", onnx.TensorProto.FLOAT, None)], [w])
    return h.make_model(graph, opset_imports=[h.make_opsetid("", 17)])


def test_an_unsupported_op_or_attribute_is_refused_by_name():
    with pytest.raises(InputError, match="op Softmax is not supported"):
        GraphModule(_tiny("Softmax"), ["y"])
    with pytest.raises(InputError, match="auto_pad"):
        GraphModule(_tiny("Conv", kernel_shape=[1, 1], auto_pad="SAME_UPPER"), ["y"])
    with pytest.raises(InputError, match="'nope'"):
        GraphModule(_tiny("Sigmoid"), ["nope"])
    net = GraphModule(_tiny("Softmax"), ["c"])  # a node the taps do not need is not built
    assert net(torch.ones(1, 3, 4, 4))[0].shape == (1, 2, 4, 4)


def test_an_op_on_the_channels_last_input_is_refused():
    h = onnx.helper
    nodes = [h.make_node("Reshape", ["x", "s"], ["y"])]
    s = onnx.numpy_helper.from_array(np.array([1, -1], np.int64), "s")
    graph = h.make_graph(nodes, "g", [h.make_tensor_value_info("x", onnx.TensorProto.FLOAT, [1, 4, 4, 3])],
                         [h.make_tensor_value_info("y", onnx.TensorProto.FLOAT, None)], [s])
    with pytest.raises(InputError, match="channels-last"):
        GraphModule(h.make_model(graph, opset_imports=[h.make_opsetid("", 17)]), ["y"])


def test_a_file_that_is_not_onnx_is_refused(tmp_path):
    bad = tmp_path / "bad.onnx"
    bad.write_bytes(b"\x0a\xff\xff\xff\xff\xff")
    with pytest.raises(InputError, match="bad.onnx"):
        load_onnx(bad)


class _WithHead(nn.Module):
    """The encoder inside a larger network: a 1x1 head on the stride-32 tap, added to the stride-16 one."""

    def __init__(self):
        super().__init__()
        self.enc = pose_encoder(taps=["t79_0", "t105_0"])
        self.head = nn.Conv2d(864, 528, 1)

    def forward(self, x):
        s16, s32 = self.enc(x)
        return s16 + nn.functional.interpolate(self.head(s32), scale_factor=2.0), s32


@pytest.mark.slow  # a dynamo export of ~100 nodes
def test_export_inside_a_network_runs_in_onnxruntime(tmp_path):
    torch.manual_seed(0)
    model = _WithHead().eval()
    batch = torch.export.Dim("batch", min=1, max=1024)
    h32, w32 = torch.export.Dim("h32", min=1, max=256), torch.export.Dim("w32", min=1, max=256)
    with torch.no_grad():
        prog = torch.onnx.export(model, (_image(2, 64),), dynamo=True, verbose=False, input_names=["image"],
                                 output_names=["fused", "s32"],
                                 dynamic_shapes={"x": {0: batch, 2: 32 * h32, 3: 32 * w32}})
    path = tmp_path / "enc.onnx"
    path.write_bytes(prog.model_proto.SerializeToString())
    x = _image(3, 128, seed=3)[:, :, :96]  # another batch and size than traced, H != W
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = 1
    ref = ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"]).run(None, {"image": x.numpy()})
    with torch.no_grad():
        got = model(x)
    for r, y in zip(ref, got, strict=True):
        assert r.shape == tuple(y.shape)
        np.testing.assert_allclose(r, y.numpy(), rtol=0, atol=1e-4 * np.abs(r).max())
