"""Converting an older checkpoint of your own (numpy values, config objects) to the current safe form.

A module of its own: it reads relightnet's ``TrainConfig`` objects, so it imports the training
module, which imports :mod:`relightnet.model.checkpoint` (no cycle).
"""

from __future__ import annotations

import dataclasses
import pickle
import re
from pathlib import Path

import torch

from ..checks import InputError
from .checkpoint import FORMAT, _validated, _write
from .network import NetConfig
from .train_config import TrainConfig

__all__ = ["convert_checkpoint"]


def _numpy_globals() -> list:
    import numpy as np

    core = np._core if hasattr(np, "_core") else np.core
    dtypes = [getattr(np.dtypes, n) for n in dir(np.dtypes) if n.endswith("DType")]
    return [core.multiarray._reconstruct, core.multiarray.scalar, np.ndarray, np.dtype, *dtypes]


def _to_plain(value, depth: int = 0):
    """numpy arrays → tensors, numpy scalars → Python numbers, config dataclasses → dicts (recursively)."""
    import numpy as np

    if depth > 32:
        raise InputError("checkpoint: nested deeper than 32 levels")
    if isinstance(value, np.ndarray):
        if value.dtype.hasobject:
            raise InputError("checkpoint: holds a numpy object array")
        return torch.from_numpy(value.astype(value.dtype.newbyteorder("="), copy=True))
    if isinstance(value, np.generic):
        return value.item()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _to_plain(dataclasses.asdict(value), depth + 1)
    if isinstance(value, dict):
        return {k: _to_plain(v, depth + 1) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_to_plain(v, depth + 1) for v in value)
    return value


def convert_checkpoint(src, dst) -> Path:
    """Rewrite an older checkpoint of your own in the current safe form.

    It is read with ``torch.load(weights_only=True)`` allowing, besides tensors and plain values,
    numpy arrays, scalars and dtypes and relightnet's own ``NetConfig``/``TrainConfig`` (rebuilt
    field by field, no code of the file runs); these become tensors, Python numbers and dicts.
    Anything else is still refused by name. The weights are copied bit for bit.

    Returns:
        ``dst``, written atomically (it may be ``src``).
    """
    src = Path(src)
    if not src.is_file():
        raise InputError(f"{src}: checkpoint not found")
    try:
        # TrainConfig was defined in .training before .train_config: older pickles name it there.
        allowed = [*_numpy_globals(), NetConfig, TrainConfig, (TrainConfig, "relightnet.model.training.TrainConfig")]
        with torch.serialization.safe_globals(allowed):
            state = torch.load(src, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as e:
        m = re.search(r"GLOBAL ([\w.]+)", str(e))
        raise InputError(f"{src}: refused: it holds {m.group(1) if m else 'an object that is not allowed'}, which "
                         "is not a tensor, plain value, numpy value or relightnet config; nothing was run") from None
    except Exception as e:
        raise InputError(f"{src}: unreadable checkpoint ({type(e).__name__})") from None
    state = _validated(_to_plain(state), src)
    state["format"] = FORMAT
    return _write(dst, state)
