"""Each ONNX op of model.onnx_ops on a small hand-made graph, against ONNX Runtime."""

import numpy as np
import onnx
import onnxruntime as ort
import pytest
import torch
from onnx import TensorProto, helper, numpy_helper

from relightnet.checks import InputError
from relightnet.model.onnx_ops import SUPPORTED_OPS
from relightnet.model.onnx_torch import GraphModule


def _graph(nodes, inits, out_shape=None, opset=13):
    x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 4, 8, 8])
    y = helper.make_tensor_value_info("y", TensorProto.FLOAT, out_shape)
    g = helper.make_graph(nodes, "g", [x], [y], [numpy_helper.from_array(a, n) for n, a in inits.items()])
    return helper.make_model(g, opset_imports=[helper.make_opsetid("", opset)])


def test_ops_match_onnxruntime():
    rng = np.random.default_rng(0)
    inits = {
        "w": rng.normal(size=(4, 2, 3, 3)).astype(np.float32),  # grouped convolution (group 2)
        "b": rng.normal(size=4).astype(np.float32),
        "lo": np.array(0.0, np.float32), "hi": np.array(6.0, np.float32),
        "pads": np.array([0, 0, 1, 1, 0, 0, 0, 0], np.int64),
        "scales": np.array([1, 1, 2, 2], np.float32), "roi": np.array([], np.float32),
    }
    nodes = [
        helper.make_node("Conv", ["x", "w", "b"], ["c"], group=2, pads=[1, 1, 1, 1], strides=[2, 2]),
        helper.make_node("Clip", ["c", "lo", "hi"], ["r"]),
        helper.make_node("Pad", ["r", "pads"], ["p"], mode="constant"),
        helper.make_node("MaxPool", ["p"], ["m"], kernel_shape=[2, 2], strides=[2, 2]),
        helper.make_node("Resize", ["m", "roi", "scales"], ["u"], mode="linear",
                         coordinate_transformation_mode="half_pixel"),
        helper.make_node("Add", ["u", "u"], ["a"]),
        helper.make_node("Sigmoid", ["a"], ["y"]),
    ]
    model = _graph(nodes, inits, [1, 4, 4, 4])
    onnx.checker.check_model(model)
    x = rng.normal(size=(1, 4, 8, 8)).astype(np.float32)
    want = ort.InferenceSession(model.SerializeToString()).run(None, {"x": x})[0]
    got = GraphModule(model, ["y"], channels_last_input=False)(torch.from_numpy(x))[0]
    # ~20 float32 operations per output, each rounding by 2^-24 relative: 1e-5 absolute on values in (0, 1).
    np.testing.assert_allclose(got.detach().numpy(), want, atol=1e-5, rtol=0)
    assert {"Conv", "Clip", "Pad", "MaxPool", "Resize", "Add", "Sigmoid"} <= set(SUPPORTED_OPS)


def test_unsupported_op_and_attribute_are_refused_by_name():
    model = _graph([helper.make_node("Softmax", ["x"], ["y"])], {})
    with pytest.raises(InputError, match="Softmax"):
        GraphModule(model, ["y"], channels_last_input=False)
    w = np.zeros((4, 4, 3, 3), np.float32)
    model = _graph([helper.make_node("Conv", ["x", "w"], ["y"], auto_pad="SAME_UPPER")], {"w": w})
    with pytest.raises(InputError, match="auto_pad"):
        GraphModule(model, ["y"], channels_last_input=False)
