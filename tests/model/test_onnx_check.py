"""ONNX graphs from strangers are checked (names, inferred shapes) before ONNX Runtime sees them."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from relightnet.checks import InputError
from relightnet.model.onnx_check import check_graph, load_graph

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "fuzz"))
from resource_cases import onnx_bytes  # noqa: E402

sys.path.pop(0)


def test_a_graph_with_an_oversized_tensor_is_refused_before_a_session(tmp_path):
    import onnx

    (tmp_path / "bomb.onnx").write_bytes(onnx_bytes(30000))
    proto = load_graph(tmp_path / "bomb.onnx")  # the names are relightnet's
    with pytest.raises(InputError, match=r"bomb.onnx: tensor 'big' would hold \[30000, 30000\]"):
        check_graph(proto, tmp_path / "bomb.onnx", 1, 64, 64)
    (tmp_path / "small.onnx").write_bytes(onnx_bytes(16))  # the same graph with a 16² constant passes
    check_graph(load_graph(tmp_path / "small.onnx"), tmp_path / "small.onnx", 2, 64, 48)
    bad = onnx.load_from_string(onnx_bytes(16))
    del bad.graph.output[1:]
    (tmp_path / "bad.onnx").write_bytes(bad.SerializeToString())
    with pytest.raises(InputError, match="bad.onnx: not a relightnet model \\(outputs"):
        load_graph(tmp_path / "bad.onnx")
    (tmp_path / "junk.onnx").write_bytes(b"\x08\x07junk" * 10)
    with pytest.raises(InputError, match="junk.onnx"):
        load_graph(tmp_path / "junk.onnx")


def test_output_shapes_must_be_the_exports(tmp_path):
    import onnx


    proto = onnx.load_from_string(onnx_bytes(16))
    for node in proto.graph.node:  # transport made of 2 image copies: 6 channels where light_raw says K = 9
        if node.op_type == "Concat":
            del node.input[2]
    path = tmp_path / "six.onnx"
    path.write_bytes(proto.SerializeToString())
    with pytest.raises(InputError, match="output 'transport' is \\[1, 6, 32, 32\\]"):
        check_graph(load_graph(path), path, 1, 32, 32)
