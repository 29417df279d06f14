"""The ONNX operators :class:`relightnet.model.onnx_torch.GraphModule` runs, each as a torch function.

A builder reads one node (its attributes and its constant inputs) once, when the module is built,
and returns a function ``fn(params, *tensors) -> tensor`` that the module calls on every forward.
Everything that is not a tensor flowing through the graph (pads, shapes, scales, clip bounds) is
read here as a Python constant, so the torch graph (and its ONNX export) sees only static numbers;
convolution weights and biases (and any other float initializer a node adds) are parameters.

Layout: a tensor may be held in a permuted layout (``perm``: held = logical.permute(perm)), which
is how a graph whose input is channels-last (NHWC, as a converted TensorFlow model's is) takes a
channels-first input: the ops up to the graph's own NHWC -> NCHW ``Transpose`` (``Pad``, the
elementwise ops) follow the permutation, and that ``Transpose`` becomes a no-op. Every other op
needs its inputs in their logical layout and refuses a permuted one.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import torch
import torch.nn.functional as F

from ..checks import InputError, ShapeError

__all__ = ["BUILDERS", "SUPPORTED_OPS", "Context"]

Fn = Callable[..., torch.Tensor]


class Context(Protocol):
    """What a builder may ask of the module being built (see ``onnx_torch._Builder``)."""

    def const(self, node, i: int, default=None):
        """Input ``i`` of ``node`` as a numpy array (an initializer); ``default`` if absent."""

    def param(self, node, i: int) -> str | None:
        """The parameter key of input ``i`` (a float initializer), None if absent."""

    def perm(self, node, i: int) -> tuple[int, ...] | None:
        """The layout of input ``i`` (None: logical)."""

    def plain(self, node, i: int = 0) -> None:
        """Refuse a permuted input ``i``."""


def _refuse(node, what: str) -> InputError:
    return InputError(f"ONNX node {node.name or node.output[0]!r} ({node.op_type}): {what}")


def _hw_pads(node, pads) -> tuple[int, int, int, int]:
    """ONNX 2-D pads (top, left, bottom, right) from the ``pads`` attribute."""
    pads = list(pads) if pads is not None else [0, 0, 0, 0]
    if len(pads) != 4:
        raise _refuse(node, f"expected 2-D pads, got {pads}")
    return tuple(int(p) for p in pads)


def _no_auto_pad(node, attrs: dict) -> None:
    auto = attrs.get("auto_pad", b"NOTSET")
    if auto not in (b"NOTSET", "NOTSET"):
        raise _refuse(node, f"auto_pad {auto!r} is not supported (explicit pads only)")


def _conv(node, attrs: dict, ctx: Context) -> tuple[Fn, object]:
    _no_auto_pad(node, attrs)
    ctx.plain(node)
    w, b = ctx.param(node, 1), ctx.param(node, 2)
    if w is None or ctx.const(node, 1).ndim != 4:
        raise _refuse(node, "only 2-D convolutions with constant weights are supported")
    top, left, bottom, right = _hw_pads(node, attrs.get("pads"))
    stride = tuple(attrs.get("strides", (1, 1)))
    dil, group = tuple(attrs.get("dilations", (1, 1))), int(attrs.get("group", 1))
    same = top == bottom and left == right

    def conv(p, x):
        if not same:
            x = F.pad(x, (left, right, top, bottom))
        return F.conv2d(x, p[w], p[b] if b else None, stride, (top, left) if same else 0, dil, group)

    return conv, None


def _maxpool(node, attrs: dict, ctx: Context) -> tuple[Fn, object]:
    _no_auto_pad(node, attrs)
    ctx.plain(node)
    if (len(node.output) > 1 and node.output[1]) or attrs.get("storage_order", 0):
        raise _refuse(node, "the Indices output and storage_order are not supported")
    kernel = tuple(attrs["kernel_shape"])
    if len(kernel) != 2:
        raise _refuse(node, f"only 2-D pooling is supported, got kernel {kernel}")
    top, left, bottom, right = _hw_pads(node, attrs.get("pads"))
    stride, dil = tuple(attrs.get("strides", (1, 1))), tuple(attrs.get("dilations", (1, 1)))
    ceil, same = bool(attrs.get("ceil_mode", 0)), top == bottom and left == right

    def maxpool(p, x):
        if not same:
            x = F.pad(x, (left, right, top, bottom), value=float("-inf"))
        return F.max_pool2d(x, kernel, stride, (top, left) if same else 0, dil, ceil_mode=ceil)

    return maxpool, None


def _clip(node, attrs: dict, ctx: Context) -> tuple[Fn, object]:
    lo, hi = ctx.const(node, 1), ctx.const(node, 2)
    lo = float(lo) if lo is not None else attrs.get("min")  # opset < 11: attributes
    hi = float(hi) if hi is not None else attrs.get("max")
    return (lambda p, x: torch.clamp(x, lo, hi)), ctx.perm(node, 0)


def _sigmoid(node, attrs: dict, ctx: Context) -> tuple[Fn, object]:
    return (lambda p, x: torch.sigmoid(x)), ctx.perm(node, 0)


def _add(node, attrs: dict, ctx: Context) -> tuple[Fn, object]:
    a, b = ctx.param(node, 0), ctx.param(node, 1)
    if a is not None or b is not None:  # a constant operand broadcasts in the logical layout only
        for i, key in enumerate((a, b)):
            if key is None:
                ctx.plain(node, i)
        perm = None
    elif ctx.perm(node, 0) != ctx.perm(node, 1):
        raise _refuse(node, "its two inputs are held in different layouts")
    else:
        perm = ctx.perm(node, 0)

    def add(p, *xs):
        it = iter(xs)
        return (p[a] if a else next(it)) + (p[b] if b else next(it))

    return add, perm


def _pad(node, attrs: dict, ctx: Context) -> tuple[Fn, object]:
    mode = attrs.get("mode", b"constant")
    if mode not in (b"constant", "constant") or (len(node.input) > 3 and node.input[3]):
        raise _refuse(node, f"only constant padding of every axis is supported, got mode {mode!r} or axes")
    pads = [int(v) for v in ctx.const(node, 1)]
    value = ctx.const(node, 2)
    value = 0.0 if value is None else float(value)
    n = len(pads) // 2
    perm = ctx.perm(node, 0) or tuple(range(n))
    begin, end = [pads[perm[k]] for k in range(n)], [pads[n + perm[k]] for k in range(n)]
    flat = tuple(v for k in reversed(range(n)) for v in (begin[k], end[k]))  # F.pad: last axis first
    return (lambda p, x: F.pad(x, flat, value=value)), ctx.perm(node, 0)


def _transpose(node, attrs: dict, ctx: Context) -> tuple[Fn, object]:
    held = ctx.perm(node, 0)
    q = attrs.get("perm")
    if q is None:
        raise _refuse(node, "a Transpose without perm (reverse all axes) is not supported")
    q = tuple(int(v) for v in q)
    if held is not None:  # held = logical.permute(held): logical = held.permute(inverse)
        inv = tuple(held.index(k) for k in range(len(held)))
        q = tuple(inv[i] for i in q)
    if q == tuple(range(len(q))):
        return (lambda p, x: x), None
    return (lambda p, x: x.permute(q)), None


def _reshape(node, attrs: dict, ctx: Context) -> tuple[Fn, object]:
    ctx.plain(node)
    shape = [int(v) for v in ctx.const(node, 1)]
    keep = not attrs.get("allowzero", 0)
    fixed = all(d > 0 for d in shape)
    total = 1
    for d in shape:
        total *= max(d, 1)

    def reshape(p, x):
        if fixed and x.numel() != total:
            raise ShapeError(f"ONNX node {node.output[0]!r} (Reshape): its fixed shape {shape} does not fit "
                             f"a tensor of shape {tuple(x.shape)} (this output needs the graph's own batch and size)")
        return x.reshape([x.shape[i] if keep and d == 0 else d for i, d in enumerate(shape)])

    return reshape, None


_RESIZE = {  # (mode, coordinate_transformation_mode) -> F.interpolate's (mode, align_corners)
    ("linear", "half_pixel"): ("bilinear", False),
    ("linear", "pytorch_half_pixel"): ("bilinear", False),  # equal unless an output length is 1
    ("linear", "align_corners"): ("bilinear", True),
    ("nearest", "asymmetric"): ("nearest", None),
}


def _resize(node, attrs: dict, ctx: Context) -> tuple[Fn, object]:
    ctx.plain(node)
    text = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in attrs.items()}
    key = (text.get("mode", "nearest"), text.get("coordinate_transformation_mode", "half_pixel"))
    bad = text.get("antialias", 0) or text.get("axes") is not None
    if key not in _RESIZE or bad or (key[0] == "nearest" and text.get("nearest_mode", "round_prefer_floor") != "floor"):
        raise _refuse(node, f"resize {key} (nearest_mode {text.get('nearest_mode')!r}) is not supported; "
                            f"supported: {sorted(_RESIZE)} (nearest with nearest_mode floor)")
    mode, corners = _RESIZE[key]
    scales, sizes = ctx.const(node, 2), ctx.const(node, 3)
    if sizes is not None and sizes.size:
        size, factor = tuple(int(v) for v in sizes[2:]), None
    elif scales is not None and len(scales) == 4 and list(scales[:2]) == [1.0, 1.0]:
        size, factor = None, tuple(float(v) for v in scales[2:])
    else:
        raise _refuse(node, "expected constant scales (1, 1, sh, sw) or sizes of a 4-D tensor")
    return (lambda p, x: F.interpolate(x, size, factor, mode=mode, align_corners=corners)), None


#: Builders by ONNX op type (default domain, opset >= 11).
BUILDERS = {"Add": _add, "Clip": _clip, "Conv": _conv, "MaxPool": _maxpool, "Pad": _pad, "Reshape": _reshape,
            "Resize": _resize, "Sigmoid": _sigmoid, "Transpose": _transpose}
#: The ONNX op types a GraphModule runs; any other op is refused when the module is built.
SUPPORTED_OPS = tuple(sorted(BUILDERS))
