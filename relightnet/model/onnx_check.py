"""ONNX graphs from strangers: only what ``relightnet export`` writes, bounded at the size it runs.

ONNX Runtime runs any graph it is given, and folds constant sub-graphs while it builds the
session: a 651-byte file with a ``ConstantOfShape`` of 30000² takes gigabytes before a frame
is fed. So before a session is made (and again for every new input size):

- the graph's inputs and outputs must be those of :func:`relightnet.model.onnx_export.export_onnx`
  (:data:`~relightnet.model.onnx_export.INPUTS`, :data:`~relightnet.model.onnx_export.OUTPUTS`,
  optionally :data:`~relightnet.model.onnx_export.EVIDENCE_OUTPUTS`);
- ONNX shape inference (with constant propagation) is run with the real input shapes; every
  tensor's shape must be inferred and hold at most
  :data:`~relightnet.model.checkpoint.MAX_ACTIVATION` elements, and the outputs must have the
  shapes the export writes.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..checks import InputError
from .checkpoint import MAX_ACTIVATION
from .onnx_export import EVIDENCE_OUTPUTS, INPUTS, OUTPUTS

__all__ = ["load_graph", "check_graph"]


def load_graph(path):
    """The graph of an ``.onnx`` file (external data not loaded), with its names checked.

    Raises:
        InputError: unreadable, or inputs/outputs other than an exported relightnet model's.
    """
    import onnx

    path = Path(path)
    try:
        proto = onnx.load(str(path), load_external_data=False)
    except Exception as e:  # noqa: BLE001 - protobuf decode errors of many kinds
        raise InputError(f"{path}: unreadable ONNX model ({type(e).__name__})") from None
    inits = {i.name for i in proto.graph.initializer}
    inputs = [i.name for i in proto.graph.input if i.name not in inits]
    outputs = [o.name for o in proto.graph.output]
    if inputs != list(INPUTS):
        raise InputError(f"{path}: not a relightnet model (inputs {inputs[:8]}, expected {list(INPUTS)})")
    if outputs not in (list(OUTPUTS), list(OUTPUTS) + list(EVIDENCE_OUTPUTS)):
        raise InputError(f"{path}: not a relightnet model (outputs {outputs[:10]}, expected {list(OUTPUTS)} "
                         f"[+ {list(EVIDENCE_OUTPUTS)}])")
    return proto


def _dims(value_info) -> list[int] | None:
    t = value_info.type.tensor_type
    if not t.HasField("shape"):
        return None
    dims = [d.dim_value if d.HasField("dim_value") else None for d in t.shape.dim]
    return None if any(d is None for d in dims) else dims


def check_graph(proto, path, batch: int, height: int, width: int) -> None:
    """Refuse a graph that at input (``batch``, 3, ``height``, ``width``) has a tensor of unknown
    shape or of more than :data:`~relightnet.model.checkpoint.MAX_ACTIVATION` elements, or outputs
    of other shapes than the export writes.

    Raises:
        InputError: one line naming the file and the tensor.
    """
    import onnx
    from onnx import shape_inference

    m = onnx.ModelProto()
    m.CopyFrom(proto)
    fixed = {"image": [batch, 3, height, width], "mask": [batch, 1, height, width], "is_first": [batch]}
    for i in m.graph.input:
        dims = i.type.tensor_type.shape.dim
        if i.name not in fixed and not all(d.HasField("dim_value") and 0 < d.dim_value <= 4096 for d in dims[1:]):
            raise InputError(f"{path}: input {i.name!r} must have fixed dimensions after the batch (as exported)")
        want = fixed.get(i.name) or [batch] + [d.dim_value for d in dims[1:]]
        if len(dims) != len(want):
            raise InputError(f"{path}: input {i.name!r} has {len(dims)} dimensions; expected {len(want)}")
        for d, n in zip(dims, want, strict=True):
            if d.HasField("dim_value") and d.dim_value != n:
                raise InputError(f"{path}: input {i.name!r} is fixed to {d.dim_value} where {n} is fed")
            d.Clear()
            d.dim_value = n
    try:
        inferred = shape_inference.infer_shapes(m, strict_mode=True, data_prop=True)
    except Exception as e:  # noqa: BLE001 - inference errors: a graph inconsistent at this size
        first = str(e).strip().splitlines()[0][:160] if str(e).strip() else type(e).__name__
        raise InputError(f"{path}: the graph's shapes do not check at {height}x{width} ({first})") from None
    for vi in list(inferred.graph.value_info) + list(inferred.graph.output):
        dims = _dims(vi)
        if dims is None:
            raise InputError(f"{path}: tensor {vi.name[:60]!r} has no inferable shape at {height}x{width}; "
                             "only graphs whose every shape is known are run")
        if math.prod(dims) > MAX_ACTIVATION:
            raise InputError(f"{path}: tensor {vi.name[:60]!r} would hold {dims} = {math.prod(dims):.3g} values; "
                             f"at most {MAX_ACTIVATION:.3g} (relightnet.model.checkpoint.MAX_ACTIVATION)")
    shapes = {o.name: _dims(o) for o in inferred.graph.output}
    raw = shapes.get("light_raw") or []
    k = raw[1] if len(raw) == 3 else 0
    want = {"albedo": [batch, 3, height, width], "transport": [batch, k, height, width],
            "light_raw": [batch, k, 3], "light_smoothed": [batch, k, 3]}
    for name, shape in want.items():
        if shapes.get(name) != shape:
            raise InputError(f"{path}: output {name!r} is {shapes.get(name)} at {height}x{width}; "
                             f"an exported relightnet model gives {shape}")
