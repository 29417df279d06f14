"""Input validation with typed, one-line errors.

Every public function validates its tensors here, so a user sees
``ShapeError: light: expected (B, K, 3), got (2, 16)`` instead of a broadcast
failure three calls deeper.

Dimension specs are lists of entries:

- an ``int`` (or a digit string such as ``"3"``) must match exactly;
- a name (``"B"``, ``"K"``, ...) matches any size, and the same name must have
  the same size everywhere within one call (pass ``dims={"K": 9}`` to pin it);
- ``"..."`` (at most once) matches any number of leading/middle dimensions.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Iterable, Mapping, Sequence

import torch

from .errors import InputError, RelightError, ShapeError

__all__ = [
    "RelightError",
    "ShapeError",
    "InputError",
    "check_shape",
    "check_finite",
    "check_unit",
    "check_dtype",
    "check_sh_count",
    "sh_order_from_count",
    "check_device",
    "check_choices",
]


def _fmt(spec: Sequence) -> str:
    return "(" + ", ".join(str(s) for s in spec) + ")"


def check_shape(
    x: torch.Tensor,
    spec: Sequence,
    name: str = "tensor",
    dims: Mapping[str, int] | None = None,
) -> dict[str, int]:
    """Check ``x.shape`` against ``spec`` and return the sizes bound to names.

    Args:
        x: tensor (or numpy array) to check.
        spec: e.g. ``["B", "K", 3]`` or ``["...", 3]``.
        name: what the user calls this input; starts the error message.
        dims: sizes already fixed for some names.

    Returns:
        ``{name: size}`` for every named dimension in ``spec``.

    Raises:
        ShapeError: ``"{name}: expected (B, K, 3), got (2, 16)"``.

    Example:
        >>> import torch
        >>> from relightnet.checks import check_shape
        >>> check_shape(torch.zeros(2, 9, 3), ["B", "K", 3], name="sh")
        {'B': 2, 'K': 9}
        >>> check_shape(torch.zeros(2, 16), ["B", "K", 3], name="sh")
        Traceback (most recent call last):
            ...
        relightnet.errors.ShapeError: sh: expected (B, K, 3), got (2, 16)
    """
    shape = tuple(x.shape)
    bound: dict[str, int] = dict(dims or {})
    spec = [s if isinstance(s, str) else str(s) for s in spec]
    if spec.count("...") > 1:
        raise ValueError("check_shape: at most one '...' in a spec")
    if "..." in spec:
        i = spec.index("...")
        head, tail = spec[:i], spec[i + 1 :]
        if len(shape) < len(head) + len(tail):
            raise _shape_error(name, spec, dims, shape)
        pairs = list(zip(head, shape[: len(head)], strict=True)) + list(
            zip(tail, shape[len(shape) - len(tail) :], strict=True)
        )
    else:
        if len(shape) != len(spec):
            raise _shape_error(name, spec, dims, shape)
        pairs = list(zip(spec, shape, strict=True))
    for s, n in pairs:
        if s.isdigit():
            if int(s) != n:
                raise _shape_error(name, spec, dims, shape)
        elif s in bound:
            if bound[s] != n:
                raise _shape_error(name, spec, dims, shape)
        else:
            bound[s] = n
    return bound


def _shape_error(name: str, spec: list, dims: Mapping[str, int] | None, shape: tuple) -> ShapeError:
    """The error of :func:`check_shape`, built only when a check fails (names pinned by ``dims``
    show their size, ``K=9``)."""
    dims = dims or {}
    expected = _fmt([f"{s}={dims[s]}" if s in dims and not s.isdigit() else s for s in spec])
    return ShapeError(f"{name}: expected {expected}, got {_fmt(shape)}")


def check_finite(x: torch.Tensor, name: str = "tensor") -> None:
    """Raise :class:`InputError` if ``x`` holds NaN or Inf.

    Integer and boolean tensors are finite by type (no work). The check reads one value back
    (``.item()``); while a graph is traced or compiled (ONNX export, ``torch.compile``) there
    is no value to read and nothing is checked.
    """
    x = torch.as_tensor(x)
    if not (x.is_floating_point() or x.is_complex()) or x.numel() == 0:
        return
    if torch.jit.is_tracing() or torch.compiler.is_compiling():
        return
    if not torch.isfinite(x).all().item():
        raise InputError(f"{name}: contains NaN or Inf values")


def check_unit(x: torch.Tensor, name: str = "dirs", atol: float = 1e-3) -> None:
    """Raise :class:`InputError` unless every vector on the last axis has unit length.

    Args:
        x: (..., 3) directions.
    """
    check_finite(x, name)
    if x.numel() == 0:
        return
    err = (x.norm(dim=-1) - 1).abs().max().item()
    if err > atol:
        raise InputError(
            f"{name}: expected unit vectors on the last axis, |norm - 1| reaches {err:.3g}"
        )


def check_dtype(x: torch.Tensor, allowed: Iterable[torch.dtype], name: str = "tensor") -> None:
    """Raise :class:`InputError` unless ``x.dtype`` is one of ``allowed``."""
    allowed = tuple(allowed)
    if x.dtype not in allowed:
        names = ", ".join(str(a).replace("torch.", "") for a in allowed)
        raise InputError(f"{name}: expected dtype in ({names}), got {str(x.dtype).replace('torch.', '')}")


def sh_order_from_count(k: int, name: str = "sh") -> int:
    """Return lmax for K = (lmax+1)² coefficients, or raise :class:`ShapeError`.

    Example:
        >>> from relightnet.checks import sh_order_from_count
        >>> sh_order_from_count(9), sh_order_from_count(16)
        (2, 3)
    """
    lmax = math.isqrt(int(k)) - 1
    if k < 1 or (lmax + 1) ** 2 != k:
        raise ShapeError(f"{name}: expected K = (lmax+1)^2 coefficients (1, 4, 9, 16, ...), got {k}")
    return lmax


def check_sh_count(x: torch.Tensor, name: str = "sh", axis: int = -2) -> int:
    """Check that axis ``axis`` of ``x`` holds a valid SH count and return lmax."""
    if x.dim() == 0 or x.dim() < abs(axis):
        raise ShapeError(f"{name}: expected an SH axis at position {axis}, got shape {tuple(x.shape)}")
    return sh_order_from_count(x.shape[axis], name)


def check_device(device, name: str = "--device") -> torch.device:
    """A torch device that exists here: ``cpu``, or ``cuda[:N]`` on a machine with CUDA.

    Raises:
        InputError: an unknown device name, or CUDA asked for where there is none.
    """
    try:
        dev = torch.device(device)
    except (RuntimeError, TypeError):
        raise InputError(f"{name} {device}: expected cpu or cuda[:N]") from None
    if dev.type == "cuda" and not torch.cuda.is_available():
        raise InputError(f"{name} {device}: CUDA is not available on this machine (use cpu)")
    if dev.type not in ("cpu", "cuda"):
        raise InputError(f"{name} {device}: expected cpu or cuda[:N]")
    return dev


def _literal_choices(hint) -> tuple | None:
    """The values of a ``Literal[...]`` annotation (also inside ``Literal[...] | None``), else None."""
    if typing.get_origin(hint) is typing.Literal:
        return typing.get_args(hint)
    for arg in typing.get_args(hint):
        if typing.get_origin(arg) is typing.Literal:
            return typing.get_args(arg)
    return None


def check_choices(config, where: str) -> None:
    """Check every ``Literal[...]``-typed field of a dataclass instance against its choices.

    A field typed ``Literal[...] | None`` may also be None.

    Args:
        config: a dataclass instance (a config).
        where: what the user calls the config; starts the error message.

    Raises:
        InputError: ``"{where} {field}: expected one of 'a', 'b', got 'c'"``.

    Example:
        >>> import typing
        >>> from dataclasses import dataclass
        >>> from relightnet.checks import check_choices
        >>> @dataclass
        ... class Run:
        ...     precision: typing.Literal["fp32", "bf16"] = "fp32"
        >>> check_choices(Run("bf16"), "train config")
        >>> check_choices(Run("fp8"), "train config")
        Traceback (most recent call last):
            ...
        relightnet.errors.InputError: train config precision: expected one of 'fp32', 'bf16', got 'fp8'
    """
    hints = typing.get_type_hints(type(config))
    for f in dataclasses.fields(config):
        choices = _literal_choices(hints.get(f.name))
        if choices is None:
            continue
        value = getattr(config, f.name)
        if value is None and type(None) in typing.get_args(hints[f.name]):
            continue
        if not isinstance(value, str | int) or isinstance(value, bool) or value not in choices:
            got = repr(value) if len(repr(value)) <= 60 else repr(value)[:57] + "..."
            raise InputError(f"{where} {f.name}: expected one of {', '.join(map(repr, choices))}, got {got}")
