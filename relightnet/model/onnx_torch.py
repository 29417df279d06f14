"""An ONNX graph run as a torch module: the shipped pose network's feature maps as an encoder.

:class:`GraphModule` interprets an ONNX ``ModelProto``: its nodes run in order as torch ops
(:mod:`relightnet.model.onnx_ops`), its float initializers are ``nn.Parameter`` (so autograd trains
them and ``requires_grad_`` freezes or thaws any node's), and it returns the tensors named by its
``taps`` (any intermediate tensor or graph output). Only the nodes those taps depend on are built
and run, so an encoder tapped up to stride 32 does not compute the unused heads. Once traced,
the module exports with ``torch.onnx.export`` as part of a larger network like any other.

Layout: the module takes channels-first input (B, C, H, W). A graph whose input is channels-last
(a converted TensorFlow model: (1, H, W, C), then a ``Transpose`` to NCHW; ``channels_last_input``)
gets the NCHW tensor as it is: the ops before that ``Transpose`` follow the permutation and the
``Transpose`` itself is skipped. Every tap comes back channels-first as the graph holds it after that
``Transpose`` (a tap taken before it, too).

:func:`pose_encoder` builds it from the shipped MediaPipe pose model (BlazePose GHUM full,
Apache-2.0, ``relightnet/weights/NOTICE``) with the taps of :data:`POSE_TAPS`.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import NamedTuple

import torch
from torch import nn

from ..checks import InputError, ShapeError
from ..segment.models import POSE_FILE
from .onnx_ops import BUILDERS, SUPPORTED_OPS
from .onnx_proto import EXTERNAL, attribute_value, model_from_bytes, to_array

__all__ = ["cut_to_outputs", "GraphModule", "Tap", "POSE_TAPS", "load_onnx", "pose_encoder", "find_stride_taps"]

#: The NHWC -> NCHW permutation of a channels-last graph input.
NCHW_FROM_NHWC = (0, 3, 1, 2)
#: Op types whose output counts as an activation when taps are found by stride.
ACTIVATIONS = ("Clip", "Relu", "Sigmoid")


class Tap(NamedTuple):
    """One feature map of an encoder: the ONNX tensor name, its stride and its channel count."""

    name: str
    stride: int
    channels: int


#: The pose encoder's taps (:func:`pose_encoder`): the last activation at each stride of the trunk
#: the pose model's heads share, found by :func:`find_stride_taps`. At input (B, 3, H, W) tap ``s``
#: is (B, channels, H / s, W / s); each is the ReLU6 expansion just before the next stride's depthwise
#: convolution (t105_0: the trunk's last activation, where the landmark and mask heads part).
POSE_TAPS = (Tap("t12_0", 2, 64), Tap("t24_0", 4, 144), Tap("t40_0", 8, 192), Tap("t79_0", 16, 528),
             Tap("t105_0", 32, 864))


def load_onnx(path=POSE_FILE):
    """An ONNX file as a model message with ``onnx.ModelProto``'s field names (:mod:`.onnx_proto`, read
    without importing ``onnx``): weights inside the file only (external data is refused)."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as err:
        raise InputError(f"{path}: not a readable ONNX file ({type(err).__name__})") from None
    model = model_from_bytes(data, str(path))
    for t in model.graph.initializer:
        if t.data_location == EXTERNAL:
            raise InputError(f"{path}: initializer {t.name!r} lives in an external file (refused)")
    return model


class _Builder:
    """Reads a graph's constants and layouts for the op builders (``onnx_ops.Context``)."""

    def __init__(self, graph, module: GraphModule) -> None:
        self.arrays = {t.name: to_array(t) for t in graph.initializer}
        self.module, self.perms, self.used = module, {}, []

    def _name(self, node, i: int) -> str | None:
        return node.input[i] if i < len(node.input) and node.input[i] else None

    def const(self, node, i: int, default=None):
        name = self._name(node, i)
        if name is None:
            return default
        if name not in self.arrays:
            raise InputError(f"ONNX node {node.output[0]!r} ({node.op_type}): input {name!r} must be a constant")
        return self.arrays[name]

    def param(self, node, i: int) -> str | None:
        name = self._name(node, i)
        if name is None or name not in self.arrays:
            if name is not None and node.op_type == "Conv":
                raise InputError(f"ONNX node {node.output[0]!r} (Conv): weight {name!r} must be a constant")
            return None
        key = self.module._parameter(name, self.arrays[name])
        self.used.append(key)
        return key

    def perm(self, node, i: int):
        return self.perms.get(self._name(node, i))

    def plain(self, node, i: int = 0) -> None:
        if self.perm(node, i) is not None:
            raise InputError(f"ONNX node {node.output[0]!r} ({node.op_type}) reads the channels-last input "
                             "before the graph's transpose to NCHW (not supported; a channels-first graph "
                             "takes channels_last_input=False)")


def cut_to_outputs(model, outputs: Sequence[str]) -> None:
    """Cut ``model`` (an ``onnx.ModelProto`` or a :func:`load_onnx` model, in place) to the nodes
    ``outputs`` need, with ``outputs`` (any tensors of the graph) as its float outputs of unknown
    shape: ONNX Runtime runs every node of a graph."""
    graph = model.graph
    sources = {t.name for t in graph.initializer} | {i.name for i in graph.input}
    order = _needed(list(graph.node), outputs, sources)
    kept = [type(graph.node[i])() for i in order]
    for k, i in zip(kept, order, strict=True):
        k.CopyFrom(graph.node[i])
    del graph.node[:], graph.output[:]
    graph.node.extend(kept)
    for name in outputs:
        out = graph.output.add()
        out.name = name
        out.type.tensor_type.elem_type = 1  # FLOAT


def _needed(nodes, taps: Sequence[str], sources: set[str]) -> list[int]:
    """Indices of the nodes the taps depend on, in graph order."""
    producer = {out: i for i, n in enumerate(nodes) for out in n.output if out}
    keep, todo = set(), [t for t in taps if t not in sources]
    while todo:
        i = producer[todo.pop()]
        if i not in keep:
            keep.add(i)
            todo.extend(x for x in nodes[i].input if x and x not in sources)
    return sorted(keep)


class GraphModule(nn.Module):
    """An ONNX graph's nodes run as torch ops, returning the tensors named by ``taps``.

    Args:
        model: an ``onnx.ModelProto`` (:func:`load_onnx`), default domain, opset >= 11, float32,
            one graph input. Ops: :data:`relightnet.model.onnx_ops.SUPPORTED_OPS`; a node the taps
            need with any other op, or an attribute an op does not support, raises ``InputError``
            naming it (nodes the taps do not need are neither checked nor built).
        taps: tensor names to return, in this order (graph outputs or any node output).
        channels_last_input: the graph's input is (B, H, W, C) and is given as (B, C, H, W)
            (module docstring); False: the input is given in the graph's own layout.

    ``forward(x)``: x (B, C, H, W) float32 (for the pose model: RGB in [0, 1], H and W multiples of
    32) -> a tuple of the taps, each (B, C_tap, H_tap, W_tap) for a feature map. A ``Reshape`` with a
    fixed shape (the pose model's heads) works at the graph's own batch and size only (``ShapeError``).

    Parameters are keyed by initializer name in ``params`` (a shared initializer is one parameter).
    """

    def __init__(self, model, taps: Sequence[str], channels_last_input: bool = True) -> None:
        super().__init__()
        graph = model.graph
        opset = max([o.version for o in model.opset_import if o.domain in ("", "ai.onnx")], default=0)
        if opset < 11:
            raise InputError(f"ONNX model: opset {opset} (expected the default domain at opset >= 11)")
        inits = {t.name for t in graph.initializer}
        inputs = [i.name for i in graph.input if i.name not in inits]
        if len(inputs) != 1:
            raise InputError(f"ONNX model: expected one graph input, got {inputs}")
        self.input_name, self.taps = inputs[0], tuple(taps)
        shape = next(i for i in graph.input if i.name == self.input_name).type.tensor_type.shape
        dims = [d.dim_value for d in shape.dim]
        self.in_channels = (dims[3] if channels_last_input else dims[1]) if len(dims) == 4 else 0  # 0: any
        known = {self.input_name} | {o for n in graph.node for o in n.output}
        for t in self.taps:
            if t not in known:
                raise InputError(f"taps: {t!r} is not a tensor of the graph")
        self.params = nn.ParameterDict()
        self._keys: dict[str, str] = {}
        self._build(graph, _needed(list(graph.node), self.taps, inits | {self.input_name}), channels_last_input)

    def _parameter(self, name: str, array) -> str:
        if name not in self._keys:
            if array.dtype.kind != "f":
                raise InputError(f"ONNX initializer {name!r}: expected floating point, got {array.dtype}")
            key = re.sub(r"\W", "_", name)
            if not key.isidentifier() or key in self.params or hasattr(self.params, key):
                key = f"p{len(self._keys)}_{key}"
            self.params[key] = nn.Parameter(torch.from_numpy(array.astype("float32")))
            self._keys[name] = key
        return self._keys[name]

    def _build(self, graph, order: list[int], channels_last: bool) -> None:
        ctx = _Builder(graph, self)
        if channels_last:
            ctx.perms[self.input_name] = NCHW_FROM_NHWC
        steps, self._node_params, self._inputs = [], {}, {}
        for i in order:
            node = graph.node[i]
            if node.domain not in ("", "ai.onnx") or node.op_type not in BUILDERS:
                raise InputError(f"ONNX node {node.output[0]!r}: op {node.domain + '.' if node.domain else ''}"
                                 f"{node.op_type} is not supported (supported: {', '.join(SUPPORTED_OPS)})")
            if len([o for o in node.output if o]) != 1:
                raise InputError(f"ONNX node {node.output[0]!r} ({node.op_type}): expected one output")
            ctx.used = []
            fn, perm = BUILDERS[node.op_type](node, _attributes(node), ctx)
            out = node.output[0]
            if perm is not None:
                ctx.perms[out] = perm
            args = tuple(x for x in node.input if x and x not in ctx.arrays)
            steps.append((fn, args, out))
            self._inputs[out] = args
            self._node_params[out] = tuple(ctx.used)
        last_use = {x: s for s, (_, args, _) in enumerate(steps) for x in args}
        self._steps = [(fn, args, out, tuple(dict.fromkeys(x for x in args if last_use[x] == s and x not in self.taps)))
                       for s, (fn, args, out) in enumerate(steps)]  # a tensor given twice (Add(u, u)) is freed once

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, ...]:
        """x (B, C, H, W) -> the taps (class docstring)."""
        if x.ndim != 4 or (self.in_channels and x.shape[1] != self.in_channels):
            raise ShapeError(f"x: expected (B, {self.in_channels or 'C'}, H, W), got {tuple(x.shape)}")
        env = {self.input_name: x}
        for fn, args, out, free in self._steps:
            env[out] = fn(self.params, *(env[a] for a in args))
            for a in free:
                del env[a]
        return tuple(env[t] for t in self.taps)

    def upstream(self, name: str) -> set[str]:
        """The tensors ``name`` is computed from (itself included), among the nodes this module runs."""
        if name not in self._inputs and name != self.input_name:
            raise InputError(f"{name!r}: not a tensor this module computes (taps {list(self.taps)})")
        seen, todo = set(), [name]
        while todo:
            t = todo.pop()
            if t not in seen:
                seen.add(t)
                todo.extend(self._inputs.get(t, ()))
        return seen

    def node_parameters(self, name: str) -> list[nn.Parameter]:
        """The parameters of the node whose output is ``name`` (its weight and bias for a Conv)."""
        if name not in self._node_params:
            raise InputError(f"{name!r}: not the output of a node this module runs")
        return [self.params[k] for k in self._node_params[name]]

    def set_trainable(self, after: str | None = None) -> GraphModule:
        """Thaw the parameters of every node ``after`` does not depend on, freeze those it does.

        ``after=None`` thaws all; ``module.requires_grad_(False)`` freezes all. A parameter shared by
        a frozen and a thawed node stays frozen. Returns the module.
        """
        frozen = set() if after is None else {k for t in self.upstream(after) for k in self._node_params.get(t, ())}
        for key, p in self.params.items():
            p.requires_grad_(key not in frozen)
        return self


def _attributes(node) -> dict:
    return {a.name: attribute_value(a) for a in node.attribute}


def find_stride_taps(model, size: int = 256) -> tuple[Tap, ...]:
    """The last activation at each stride of a graph's trunk, run at input (1, 3, size, size).

    The trunk is what every graph output depends on; an activation is a ``Clip``, ``Relu`` or
    ``Sigmoid`` output; stride = size / the map's height. Returns taps by increasing stride.
    """
    names = [n.output[0] for n in model.graph.node]
    outputs = [o.name for o in model.graph.output]
    full = GraphModule(model, names)
    trunk = set.intersection(*(full.upstream(o) for o in outputs))
    with torch.no_grad():
        maps = dict(zip(names, full(torch.zeros(1, 3, size, size)), strict=True))
    found: dict[int, Tap] = {}
    for node in model.graph.node:
        y = maps[node.output[0]]
        if node.op_type in ACTIVATIONS and node.output[0] in trunk and y.ndim == 4 and size % y.shape[2] == 0:
            found[size // y.shape[2]] = Tap(node.output[0], size // y.shape[2], y.shape[1])
    return tuple(found[s] for s in sorted(found))


def pose_encoder(taps: Sequence[str] | None = None, train_after: str | int | None = None,
                 path=POSE_FILE) -> GraphModule:
    """The shipped pose model's trunk as a frozen encoder (:data:`POSE_TAPS`).

    Args:
        taps: tensor names to return (default: the five of :data:`POSE_TAPS`, strides 2 to 32).
        train_after: None keeps every parameter frozen; a stride of :data:`POSE_TAPS` (2, 4, 8, 16)
            or a tensor name thaws the nodes after that tap (``16``: the stride-32 stage,
            t80_0 .. t105_0), the earlier ones stay frozen.
        path: the ONNX file (default: ``relightnet/weights/person_pose.onnx``).

    Returns:
        A :class:`GraphModule`: x (B, 3, H, W) RGB in [0, 1], H and W multiples of 32 -> a tuple of
        (B, C_s, H / s, W / s) per tap (for the default taps: C = 64, 144, 192, 528, 864 at
        s = 2, 4, 8, 16, 32).
    """
    enc = GraphModule(load_onnx(path), [t.name for t in POSE_TAPS] if taps is None else list(taps))
    enc.requires_grad_(False)
    if isinstance(train_after, int):
        by_stride = {t.stride: t.name for t in POSE_TAPS}
        if train_after not in by_stride:
            raise InputError(f"train_after: expected a stride of {sorted(by_stride)} or a tensor name, "
                             f"got {train_after}")
        train_after = by_stride[train_after]
    if train_after is not None:
        enc.set_trainable(after=train_after)
    return enc
