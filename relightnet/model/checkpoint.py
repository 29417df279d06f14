"""Checkpoints: atomic save, validated load, and the shipped model.

A checkpoint is a ``torch.save`` dict: ``format`` (a version tag), ``net_config``, ``model``
(state dict), ``step``, ``input_size`` (side of the training images), and for training runs
``optimizer``, ``scheduler``, ``train_config`` and ``rng`` (torch's CPU RNG state).
"""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path

import torch

from ..checks import InputError, check_device
from ..io import atomic_write
from .network import NetConfig, RelightNet

__all__ = ["FORMAT", "SHIPPED", "save_checkpoint", "load_checkpoint", "load_model", "shipped_checkpoint",
           "release_checkpoint"]

FORMAT = "relightnet-ckpt-1"
#: The pretrained model shipped in the package.
SHIPPED = Path(__file__).resolve().parents[1] / "weights" / "relightnet_small.pt"


def save_checkpoint(path, model: RelightNet, net_config: NetConfig, step: int = 0, optimizer=None, scheduler=None,
                    train_config: dict | None = None, **extra) -> Path:
    """Write a checkpoint atomically (a crash never leaves a truncated file)."""
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


def _write(path, state: dict) -> Path:
    """torch.save into memory, then one atomic file write."""
    buf = io.BytesIO()
    torch.save(state, buf)
    with atomic_write(path) as f:
        f.write(buf.getvalue())
    return Path(path)


def load_checkpoint(path, map_location="cpu") -> dict:
    """Read and validate a checkpoint dict; one clear error for every way it can be wrong."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: checkpoint not found")
    try:
        state = torch.load(path, map_location=map_location, weights_only=False)
    except Exception as e:  # truncated zip, pickle errors, not a torch file, ...
        raise InputError(f"{path}: unreadable checkpoint ({type(e).__name__})") from None
    if not isinstance(state, dict) or state.get("format") != FORMAT:
        raise InputError(f"{path}: not a relightnet checkpoint (expected format {FORMAT!r})")
    for key in ("net_config", "model", "step"):
        if key not in state:
            raise InputError(f"{path}: checkpoint lacks {key!r}")
    return state


def shipped_checkpoint() -> Path:
    """Path of the shipped pretrained model (raises if the package was installed without it)."""
    if not SHIPPED.is_file():
        raise InputError(f"{SHIPPED}: the shipped model is missing from this installation")
    return SHIPPED


def load_model(path=None, device="cpu") -> RelightNet:
    """A :class:`RelightNet` in eval mode from a checkpoint (default: the shipped model)."""
    device = check_device(device, "device")
    path = shipped_checkpoint() if path is None else Path(path)
    state = load_checkpoint(path, map_location=device)
    try:
        cfg = NetConfig(**state["net_config"])
    except TypeError as e:
        raise InputError(f"{path}: unknown network configuration ({e})") from None
    model = RelightNet(cfg)
    try:
        model.load_state_dict(state["model"])
    except RuntimeError as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else "state dict mismatch"
        raise InputError(f"{path}: weights do not match the network configuration ({first})") from None
    #: The side of the square crops it was trained on: the natural working size for inference.
    model.input_size = int(state.get("input_size", 256))
    return model.to(device).eval()


def release_checkpoint(src, dst, **extra) -> Path:
    """Copy a training checkpoint without its optimiser/scheduler state (what ships), adding ``extra`` keys."""
    state = load_checkpoint(src)
    for key in ("optimizer", "scheduler", "rng"):
        state.pop(key, None)
    state.update(extra)
    return _write(dst, state)
