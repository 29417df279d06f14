"""Read an ONNX file without the ``onnx`` package: the parts of the format a :class:`GraphModule` runs.

Importing ``onnx`` costs about a second on these CPUs (most of it its ``ml_dtypes`` dependency
registering number types), and every command that loads the CNN builds the pose encoder from the
shipped ONNX file. The file is a protocol buffer (``onnx.ModelProto``); this module declares the
messages and fields the encoder reads (their numbers and types as the ONNX format defines them) in a
private descriptor pool, so protobuf's own parser reads the file. Fields not declared here are kept
as unknown fields: a model read here serialises back to the same model.

The messages have the field names of ``onnx``'s, so code that reads an ``onnx.ModelProto``
(``model.graph.node``, ``tensor.raw_data``, ...) reads these too; :func:`to_array` and
:func:`attribute_value` work on either kind.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..checks import InputError

__all__ = ["EXTERNAL", "attribute_value", "model_from_bytes", "to_array"]

#: ``TensorProto.data_location`` of a tensor whose values live in another file
EXTERNAL = 1

_I64, _I32, _F32, _F64, _U64, _STR, _BYTES, _MSG = 3, 5, 2, 1, 4, 9, 12, 11
_OPT, _REP = 1, 3

# message -> (field name, number, type, label, message type or None, packed)
_SCHEMA = {
    "Model": [("ir_version", 1, _I64, _OPT, None, False), ("producer_name", 2, _STR, _OPT, None, False),
              ("graph", 7, _MSG, _OPT, "Graph", False), ("opset_import", 8, _MSG, _REP, "OpsetId", False)],
    "OpsetId": [("domain", 1, _STR, _OPT, None, False), ("version", 2, _I64, _OPT, None, False)],
    "Graph": [("node", 1, _MSG, _REP, "Node", False), ("name", 2, _STR, _OPT, None, False),
              ("initializer", 5, _MSG, _REP, "Tensor", False), ("input", 11, _MSG, _REP, "ValueInfo", False),
              ("output", 12, _MSG, _REP, "ValueInfo", False), ("value_info", 13, _MSG, _REP, "ValueInfo", False)],
    "Node": [("input", 1, _STR, _REP, None, False), ("output", 2, _STR, _REP, None, False),
             ("name", 3, _STR, _OPT, None, False), ("op_type", 4, _STR, _OPT, None, False),
             ("attribute", 5, _MSG, _REP, "Attribute", False), ("domain", 7, _STR, _OPT, None, False)],
    "Attribute": [("name", 1, _STR, _OPT, None, False), ("f", 2, _F32, _OPT, None, False),
                  ("i", 3, _I64, _OPT, None, False), ("s", 4, _BYTES, _OPT, None, False),
                  ("t", 5, _MSG, _OPT, "Tensor", False), ("g", 6, _MSG, _OPT, "Graph", False),
                  ("floats", 7, _F32, _REP, None, False), ("ints", 8, _I64, _REP, None, False),
                  ("strings", 9, _BYTES, _REP, None, False), ("tensors", 10, _MSG, _REP, "Tensor", False),
                  ("graphs", 11, _MSG, _REP, "Graph", False), ("type", 20, _I32, _OPT, None, False)],
    "Tensor": [("dims", 1, _I64, _REP, None, False), ("data_type", 2, _I32, _OPT, None, False),
               ("float_data", 4, _F32, _REP, None, True), ("int32_data", 5, _I32, _REP, None, True),
               ("int64_data", 7, _I64, _REP, None, True), ("name", 8, _STR, _OPT, None, False),
               ("raw_data", 9, _BYTES, _OPT, None, False), ("double_data", 10, _F64, _REP, None, True),
               ("uint64_data", 11, _U64, _REP, None, True), ("data_location", 14, _I32, _OPT, None, False)],
    "ValueInfo": [("name", 1, _STR, _OPT, None, False), ("type", 2, _MSG, _OPT, "Type", False)],
    "Type": [("tensor_type", 1, _MSG, _OPT, "TensorType", False)],
    "TensorType": [("elem_type", 1, _I32, _OPT, None, False), ("shape", 2, _MSG, _OPT, "Shape", False)],
    "Shape": [("dim", 1, _MSG, _REP, "Dimension", False)],
    "Dimension": [("dim_value", 1, _I64, _OPT, None, False), ("dim_param", 2, _STR, _OPT, None, False)],
}
_PACKAGE = "relightnet_onnx"


@lru_cache(maxsize=1)
def _model_class():
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    file = descriptor_pb2.FileDescriptorProto(name="relightnet_onnx.proto", package=_PACKAGE, syntax="proto2")
    for message, fields in _SCHEMA.items():
        m = file.message_type.add(name=message)
        for name, number, kind, label, ref, packed in fields:
            f = m.field.add(name=name, number=number, type=kind, label=label)
            if ref is not None:
                f.type_name = f".{_PACKAGE}.{ref}"
            if packed:
                f.options.packed = True
    pool = descriptor_pool.DescriptorPool()
    pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(f"{_PACKAGE}.Model"))


def model_from_bytes(data: bytes, name: str = "ONNX file"):
    """Parse an ONNX file's bytes into a model message with ``onnx.ModelProto``'s field names.

    Raises:
        InputError: the bytes are not a protocol buffer of that shape (names ``name``).
    """
    from google.protobuf.message import DecodeError

    try:
        return _model_class().FromString(data)
    except (DecodeError, RuntimeError) as err:
        raise InputError(f"{name}: not a readable ONNX file ({type(err).__name__})") from None


#: TensorProto.data_type -> (numpy dtype, the repeated field holding the values when raw_data is empty)
_TYPES = {1: ("<f4", "float_data"), 2: ("u1", "int32_data"), 3: ("i1", "int32_data"), 6: ("<i4", "int32_data"),
          7: ("<i8", "int64_data"), 9: ("?", "int32_data"), 10: ("<f2", "int32_data"), 11: ("<f8", "double_data")}


def to_array(tensor) -> np.ndarray:
    """A tensor message's values as a writable numpy array of its shape (``dims``).

    Works on ``onnx.TensorProto`` and on this module's tensors; float, double, float16, int8/32/64,
    uint8 and bool. Raises ``InputError`` naming the tensor for any other type, values stored in
    another file, or a value count that does not match the shape."""
    name = tensor.name or "(unnamed)"
    if tensor.data_type not in _TYPES:
        raise InputError(f"ONNX tensor {name!r}: data type {tensor.data_type} is not supported")
    if tensor.data_location == EXTERNAL:
        raise InputError(f"ONNX tensor {name!r}: its values live in an external file (refused)")
    dtype, field = _TYPES[tensor.data_type]
    shape = tuple(int(d) for d in tensor.dims)
    count = math.prod(shape)
    if tensor.raw_data:
        if len(tensor.raw_data) != count * np.dtype(dtype).itemsize:
            raise InputError(f"ONNX tensor {name!r}: {len(tensor.raw_data)} bytes for shape {shape}")
        return np.frombuffer(tensor.raw_data, dtype=dtype).reshape(shape).copy()
    values = getattr(tensor, field)
    if len(values) != count:
        raise InputError(f"ONNX tensor {name!r}: {len(values)} values for shape {shape}")
    if tensor.data_type == 10:  # float16 values are stored as their 16 bits in int32_data
        return np.asarray(values, dtype=np.uint16).view(np.float16).reshape(shape)
    return np.asarray(values, dtype=dtype).reshape(shape)


#: AttributeProto.type -> the field holding its value
_ATTRIBUTE_FIELDS = {1: "f", 2: "i", 3: "s", 4: "t", 5: "g", 6: "floats", 7: "ints", 8: "strings", 9: "tensors",
                     10: "graphs"}


def attribute_value(attribute):
    """An attribute message's value: a float, int, bytes, tensor or graph message, or a list of them.

    Raises ``InputError`` naming the attribute when its type is missing or not one of those."""
    field = _ATTRIBUTE_FIELDS.get(attribute.type)
    if field is None:
        raise InputError(f"ONNX attribute {attribute.name!r}: type {attribute.type} is not supported")
    value = getattr(attribute, field)
    return list(value) if attribute.type >= 6 else value
