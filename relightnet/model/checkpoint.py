"""Checkpoints: atomic save, safe validated load, and the shipped model.

A checkpoint is a ``torch.save`` dict of tensors and plain Python values only (dicts, lists,
tuples, strings, numbers, booleans, None; configs as dicts): ``format`` (a version tag),
``net_config`` (with ``input_size``, the side of the training images), ``model`` (state dict),
``step``, and for training runs ``optimizer``, ``scheduler``,
``train_config`` and ``rng`` (torch's CPU RNG state). :func:`save_checkpoint` refuses anything else, and
:func:`load_checkpoint` reads with ``torch.load(weights_only=True)``: a file that names any
other Python object is refused by name and nothing in it runs. A checkpoint of your own
that holds numpy values or config objects (older code) converts with
:func:`relightnet.model.convert.convert_checkpoint` (``relightnet convert-checkpoint OLD NEW``).
"""

from __future__ import annotations

import dataclasses
import io
import math
import pickle
import re
from pathlib import Path

import torch

from ..checks import InputError, check_device
from ..io import atomic_write
from ..io.documents import clip, short
from .network import NetConfig, RelightNet

__all__ = ["FORMAT", "SHIPPED", "MAX_PARAMETERS", "MAX_ACTIVATION", "save_checkpoint", "load_checkpoint",
           "load_model", "shipped_checkpoint", "release_checkpoint", "average_checkpoints"]

FORMAT = "relightnet-ckpt-2"
#: Formats read: 1 had the same plain content (it loads with ``weights_only=True`` too).
READ_FORMATS = ("relightnet-ckpt-1", FORMAT)
#: The pretrained model shipped in the package.
SHIPPED = Path(__file__).resolve().parents[1] / "weights" / "relightnet_small.pt"
#: Largest integer accepted in a checkpoint's network configuration (sizes, levels, orders).
_MAX_CONFIG_INT = 4096
#: Most parameters of a checkpoint's network (counted on the meta device before anything is
#: allocated): 64 M float32 parameters are 256 MB; the shipped network has 1.9 M.
MAX_PARAMETERS = 64_000_000
#: Most activation elements of one feature map at the working size (input_size² × width):
#: 2²⁷ float32 values are 512 MB, which keeps a forward pass within the 2 GB budget.
MAX_ACTIVATION = 1 << 27
#: Most values and containers walked in a checkpoint's plain (non-tensor) content.
_MAX_NODES = 100_000
_PLAIN = (str, int, float, bool, type(None), torch.Tensor)


def save_checkpoint(path, model: RelightNet, net_config: NetConfig, step: int = 0, optimizer=None, scheduler=None,
                    train_config: dict | None = None, **extra) -> Path:
    """Write a checkpoint atomically (a crash never leaves a truncated file).

    The working size is ``net_config["input_size"]``; an ``input_size`` in ``extra`` sets it.
    """
    if "input_size" in extra:
        net_config = dataclasses.replace(net_config, input_size=extra.pop("input_size"))
    state = {
        "format": FORMAT,
        "net_config": dataclasses.asdict(net_config),
        "model": model.state_dict(),
        "step": int(step),
        "rng": torch.get_rng_state(),
        **extra,
    }
    if optimizer is not None:
        state["optimizer"] = optimizer.state_dict()
    if scheduler is not None:
        state["scheduler"] = scheduler.state_dict()
    if train_config is not None:
        state["train_config"] = train_config
    return _write(path, state)


def _check_plain(value, where: str = "checkpoint", depth: int = 0, seen: list | None = None) -> None:
    """Raise TypeError unless ``value`` is tensors and plain Python values all the way down.

    At most :data:`_MAX_NODES` values are walked: shared containers (a pickle's memo can make
    one list appear exponentially often) end the walk instead of making it exponential.
    """
    seen = [0] if seen is None else seen
    seen[0] += 1
    if seen[0] > _MAX_NODES:
        raise TypeError(f"{where}: more than {_MAX_NODES} values (or one container shared many times)")
    if depth > 32:
        raise TypeError(f"{where}: nested deeper than 32 levels")
    if isinstance(value, dict):
        for k, v in value.items():
            if not isinstance(k, (str, int)):
                raise TypeError(f"{where}: key {short(k, 40)} is a {type(k).__name__}; keys are strings or integers")
            _check_plain(v, f"{where}[{short(k, 40)}]", depth + 1, seen)
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_plain(v, f"{where}[{i}]", depth + 1, seen)
    elif not isinstance(value, _PLAIN):
        raise TypeError(f"{where} is a {type(value).__module__}.{type(value).__name__}; a checkpoint holds "
                        "tensors and plain Python values only (configs as dicts)")


def _write(path, state: dict) -> Path:
    """Check the content is plain, torch.save into memory, then one atomic file write."""
    _check_plain(state)
    buf = io.BytesIO()
    torch.save(state, buf)
    with atomic_write(path) as f:
        f.write(buf.getvalue())
    return Path(path)


def _refused(path: Path, err: Exception) -> InputError:
    what = re.search(r"GLOBAL ([\w.]+)", str(err)).group(1)
    return InputError(
        f"{path}: refused: the checkpoint holds {what} (only tensors and plain values are loaded; nothing in it "
        f"was run); a relightnet checkpoint of your own with numpy values or config objects converts with "
        f"'relightnet convert-checkpoint {path} NEW.pt'"
    )


def load_checkpoint(path, map_location="cpu") -> dict:
    """Read and validate a checkpoint dict; one clear error for every way it can be wrong.

    Reads with ``torch.load(weights_only=True)``: no code in the file runs.

    Raises:
        InputError: missing, unreadable, refused (names the object it would need), or not a
            relightnet checkpoint.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: checkpoint not found")
    try:
        state = torch.load(path, map_location=map_location, weights_only=True)
    except pickle.UnpicklingError as e:
        if re.search(r"GLOBAL [\w.]+", str(e)):
            raise _refused(path, e) from None
        raise InputError(f"{path}: unreadable checkpoint (UnpicklingError)") from None
    except Exception as e:  # truncated zip, bad records, not a torch file, ...
        raise InputError(f"{path}: unreadable checkpoint ({type(e).__name__})") from None
    return _validated(state, path)


def _validated(state, path: Path) -> dict:
    if not isinstance(state, dict) or state.get("format") not in READ_FORMATS:
        raise InputError(f"{path}: not a relightnet checkpoint (expected format {FORMAT!r})")
    for key in ("net_config", "model", "step"):
        if key not in state:
            raise InputError(f"{path}: checkpoint lacks {key!r}")
    if not isinstance(state["net_config"], dict):
        raise InputError(f"{path}: 'net_config' is not a dict")
    model = state["model"]
    if not isinstance(model, dict) or not all(isinstance(k, str) and isinstance(v, torch.Tensor)
                                              for k, v in model.items()):
        raise InputError(f"{path}: 'model' is not a state dict (names to tensors)")
    if not isinstance(state["step"], int) or isinstance(state["step"], bool) or state["step"] < 0:
        raise InputError(f"{path}: 'step' is not a non-negative integer")
    return state


def _net_config(state: dict, path: Path) -> NetConfig:
    """The :class:`NetConfig` of a checkpoint: known keys, each of its field's type, integers in range."""
    fields = {f.name: f for f in dataclasses.fields(NetConfig)}
    for key, value in state["net_config"].items():
        if key not in fields:
            raise InputError(f"{path}: unknown network configuration key {short(key, 40)}")
        default = fields[key].default
        kind = None if default is dataclasses.MISSING or default is None else type(default)
        if kind is not None and (type(value) is not kind and not (kind is float and type(value) is int)):
            raise InputError(f"{path}: net_config {key!r}: expected a {kind.__name__}, got {short(value)}")
        if type(value) is int and not 0 <= value <= _MAX_CONFIG_INT:
            raise InputError(f"{path}: net_config {key!r}: {value} is outside [0, {_MAX_CONFIG_INT}]")
    try:
        return NetConfig(**state["net_config"])
    except (TypeError, ValueError) as e:
        raise InputError(f"{path}: unknown network configuration ({clip(str(e), 160)})") from None


def _network(cfg: NetConfig, weights: dict, path: Path) -> RelightNet:
    """Build the network for ``cfg`` and load ``weights``; shapes are compared on the meta device
    first, so a configuration that does not match the file allocates nothing."""
    try:
        with torch.device("meta"):
            shapes = {k: tuple(v.shape) for k, v in RelightNet(cfg).state_dict().items()}
    except (TypeError, ValueError, RuntimeError, InputError) as e:
        raise InputError(f"{path}: unusable network configuration ({type(e).__name__}: {clip(str(e), 160)})") \
            from None
    count = sum(math.prod(s) for s in shapes.values())
    if count > MAX_PARAMETERS:
        raise InputError(f"{path}: the network has {count / 1e6:.1f} M parameters; at most "
                         f"{MAX_PARAMETERS / 1e6:.0f} M are loaded (relightnet.model.checkpoint.MAX_PARAMETERS)")
    feature = cfg.input_size ** 2 * cfg.width
    if feature > MAX_ACTIVATION:
        raise InputError(f"{path}: input_size {cfg.input_size} × width {cfg.width} makes feature maps of "
                         f"{feature / 1e6:.0f} M values; at most {MAX_ACTIVATION / 1e6:.0f} M (MAX_ACTIVATION)")
    for k, v in weights.items():
        expanded = any(st == 0 and n > 1 for st, n in zip(v.stride(), v.shape, strict=True))
        if expanded or v.untyped_storage().nbytes() < v.numel() * v.element_size():
            raise InputError(f"{path}: weight {short(k, 60)} {tuple(v.shape)} is expanded from "
                             f"{v.untyped_storage().nbytes()} bytes of data (stride 0); weights must hold their values")
    got = {k: tuple(v.shape) for k, v in weights.items()}
    bad = next((k for k, v in weights.items() if v.is_floating_point() and not bool(torch.isfinite(v).all())), None)
    if bad is not None:
        raise InputError(f"{path}: weight {bad!r} holds NaN or Inf values")
    if shapes != got:
        diff = sorted(set(shapes) ^ set(got)) or [k for k in shapes if shapes[k] != got[k]]
        raise InputError(f"{path}: weights do not match the network configuration (first difference: {diff[0]!r})")
    model = RelightNet(cfg)
    try:
        model.load_state_dict(weights)
    except RuntimeError as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else "state dict mismatch"
        raise InputError(f"{path}: weights do not match the network configuration ({first})") from None
    return model


def shipped_checkpoint() -> Path:
    """Path of the shipped pretrained model (raises if the package was installed without it)."""
    if not SHIPPED.is_file():
        raise InputError(f"{SHIPPED}: the shipped model is missing from this installation")
    return SHIPPED


def load_model(path=None, device="cpu") -> RelightNet:
    """A :class:`RelightNet` in eval mode from a checkpoint (default: the shipped model)."""
    device = check_device(device, "device")
    path = shipped_checkpoint() if path is None else Path(path)
    state = load_checkpoint(path, map_location="cpu")
    cfg = _net_config(state, path)
    # The side of the square crops it was trained on (its working size): the configuration's, or the
    # top-level key of a checkpoint written before it was part of the configuration (the shipped one).
    size = state.get("input_size", cfg.input_size)
    if type(size) is not int or not 16 <= size <= _MAX_CONFIG_INT:
        raise InputError(f"{path}: 'input_size' {size!r} is not a size in pixels")
    model = _network(dataclasses.replace(cfg, input_size=size), state["model"], path)
    return model.to(device).eval()


def release_checkpoint(src, dst, **extra) -> Path:
    """Copy a training checkpoint without its optimiser/scheduler state (what ships), adding ``extra`` keys."""
    state = load_checkpoint(src)
    for key in ("optimizer", "scheduler", "rng"):
        state.pop(key, None)
    state.update(extra)
    state["format"] = FORMAT
    return _write(dst, state)


def average_checkpoints(srcs, dst, weights=None) -> Path:
    """A checkpoint whose weights are a weighted mean of several of the same network's.

    Averaging the weights of runs that share their start (a network and its own continuation) is a
    cheap ensemble in one network (Wortsman et al. 2022, "Model soups"). The result has no optimiser,
    schedule or RNG state (a later run starts from it with ``init``); its metadata is the last
    source's, plus ``averaged_from``: one ``{"file", "step", "weight"}`` per source.

    Args:
        srcs: two or more checkpoint paths with the same ``net_config`` and the same tensor names and shapes.
        dst: output path (written atomically).
        weights: one non-negative number per source, summing to more than 0 (normalised to 1);
            None: equal weights.

    Returns:
        ``dst`` as a Path.
    """
    srcs = [Path(p) for p in srcs]
    if len(srcs) < 2:
        raise InputError(f"srcs: expected two or more checkpoints, got {len(srcs)}")
    w = [1.0] * len(srcs) if weights is None else [float(x) for x in weights]
    if len(w) != len(srcs) or not all(math.isfinite(x) and x >= 0 for x in w) or sum(w) <= 0:
        raise InputError(f"weights: expected {len(srcs)} finite numbers >= 0 with a positive sum, got {weights!r}")
    w = [x / sum(w) for x in w]
    states = [load_checkpoint(p) for p in srcs]
    first = states[0]

    def shapes(st):
        return {k: tuple(v.shape) for k, v in st["model"].items()}

    first_cfg = _net_config(first, srcs[0])
    for p, st in zip(srcs[1:], states[1:], strict=True):
        if _net_config(st, p) != first_cfg:  # parsed: a key added since, at its default, is the same network
            raise InputError(f"{p}: another network than {srcs[0]} (net_config differs); only one network's "
                             "checkpoints are averaged")
        if shapes(st) != shapes(first):
            raise InputError(f"{p}: its tensors' names or shapes differ from {srcs[0]}'s")
    model = {}
    for name, last in states[-1]["model"].items():
        if last.is_floating_point():
            acc = sum(x * st["model"][name].double() for x, st in zip(w, states, strict=True))
            model[name] = acc.to(last.dtype)
        else:
            model[name] = last.clone()
    out = {k: v for k, v in states[-1].items() if k not in ("optimizer", "scheduler", "rng")}
    out.update(model=model, format=FORMAT, averaged_from=[
        {"file": p.name, "step": st["step"], "weight": x} for p, st, x in zip(srcs, states, w, strict=True)])
    return _write(dst, out)
