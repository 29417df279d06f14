"""The ONNX reader without ``onnx``: the same model, arrays and attributes as ``onnx``'s own reader."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.model.onnx_proto import attribute_value, model_from_bytes, to_array
from relightnet.model.onnx_torch import load_onnx
from relightnet.segment.models import POSE_FILE, SELFIE_FILE

onnx = pytest.importorskip("onnx")


@pytest.mark.parametrize("path", [POSE_FILE, SELFIE_FILE], ids=["pose", "selfie"])
def test_the_shipped_models_read_as_onnx_reads_them(path):
    ours, ref = load_onnx(path), onnx.load(str(path))
    assert [(o.domain, o.version) for o in ours.opset_import] == [(o.domain, o.version) for o in ref.opset_import]
    assert len(ours.graph.node) == len(ref.graph.node) > 100
    for a, b in zip(ours.graph.node, ref.graph.node, strict=True):
        assert (a.op_type, a.domain, list(a.input), list(a.output)) == (b.op_type, b.domain, list(b.input),
                                                                         list(b.output))
        for x, y in zip(a.attribute, b.attribute, strict=True):
            got, want = attribute_value(x), onnx.helper.get_attribute_value(y)
            assert x.name == y.name and type(got) is type(want) and got == want, x.name
    for a, b in zip(ours.graph.initializer, ref.graph.initializer, strict=True):
        got, want = to_array(a), onnx.numpy_helper.to_array(b)
        assert a.name == b.name and got.dtype == want.dtype and np.array_equal(got, want), a.name
        assert got.flags.writeable
    dims = [d.dim_value for d in ours.graph.input[0].type.tensor_type.shape.dim]
    assert dims == [d.dim_value for d in ref.graph.input[0].type.tensor_type.shape.dim]
    # fields this reader does not declare are kept: the model serialises back to the same model
    assert onnx.ModelProto.FromString(ours.SerializeToString()) == ref


@pytest.mark.parametrize("values", [np.arange(6, dtype=np.float32).reshape(2, 3) / 7,
                                    np.array([[-3, 2**40]], np.int64), np.array([1, -2, 3], np.int32),
                                    np.array([0.5, -1.25], np.float16), np.array([True, False]),
                                    np.array([1.0 / 3], np.float64), np.array([200, 3], np.uint8),
                                    np.zeros((0, 4), np.float32)],
                         ids=["float", "int64", "int32", "float16", "bool", "double", "uint8", "empty"])
@pytest.mark.parametrize("raw", [True, False], ids=["raw", "typed"])
def test_tensors_of_each_type_and_storage(values, raw):
    kind = onnx.helper.np_dtype_to_tensor_dtype(values.dtype)
    t = onnx.helper.make_tensor("t", kind, values.shape, values.tobytes() if raw else values.ravel().tolist(),
                                raw=raw)
    model = onnx.helper.make_model(onnx.helper.make_graph([], "g", [], [], [t]))
    got = to_array(model_from_bytes(model.SerializeToString()).graph.initializer[0])
    assert got.dtype == values.dtype and got.shape == values.shape and np.array_equal(got, values)


def _tensor_model(t) -> bytes:
    return onnx.helper.make_model(onnx.helper.make_graph([], "g", [], [], [t])).SerializeToString()


def test_bad_tensors_are_refused_by_name():
    short = onnx.TensorProto(name="short", data_type=onnx.TensorProto.FLOAT, dims=[2, 3], raw_data=b"\0" * 20)
    with pytest.raises(InputError, match="'short'.*20 bytes"):
        to_array(model_from_bytes(_tensor_model(short)).graph.initializer[0])
    few = onnx.TensorProto(name="few", data_type=onnx.TensorProto.INT64, dims=[4], int64_data=[1, 2, 3])
    with pytest.raises(InputError, match="'few'.*3 values"):
        to_array(model_from_bytes(_tensor_model(few)).graph.initializer[0])
    text = onnx.helper.make_tensor("text", onnx.TensorProto.STRING, [1], [b"a"])
    with pytest.raises(InputError, match="'text'.*data type 8"):
        to_array(model_from_bytes(_tensor_model(text)).graph.initializer[0])
    far = onnx.helper.make_tensor("far", onnx.TensorProto.FLOAT, [1], [1.0])
    far.data_location = onnx.TensorProto.EXTERNAL
    with pytest.raises(InputError, match="'far'.*external"):
        to_array(model_from_bytes(_tensor_model(far)).graph.initializer[0])


def test_attributes_of_each_type_and_an_untyped_one():
    node = onnx.helper.make_node("X", [], ["y"], f=0.5, i=-7, s="same", fs=[1.0, 2.5], ints=[3, 4], ss=["a", "b"])
    model = onnx.helper.make_model(onnx.helper.make_graph([node], "g", [], []))
    got = {a.name: attribute_value(a) for a in model_from_bytes(model.SerializeToString()).graph.node[0].attribute}
    assert got == {"f": 0.5, "i": -7, "s": b"same", "fs": [1.0, 2.5], "ints": [3, 4], "ss": [b"a", b"b"]}
    untyped = onnx.AttributeProto(name="odd", i=3)
    model.graph.node[0].attribute.append(untyped)
    with pytest.raises(InputError, match="'odd'"):
        [attribute_value(a) for a in model_from_bytes(model.SerializeToString()).graph.node[0].attribute]


def test_bytes_that_are_not_a_model_name_the_file():
    with pytest.raises(InputError, match="clip.onnx: not a readable ONNX file"):
        model_from_bytes(b"\x0a\xff\xff\xff\xff\xff", "clip.onnx")


@pytest.mark.slow
def test_building_the_pose_encoder_does_not_import_onnx():
    code = ("import sys; from relightnet.model import pose_encoder; pose_encoder(); "
            "print('onnx' in sys.modules, 'ml_dtypes' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert out.stdout.split() == ["False", "False"]
