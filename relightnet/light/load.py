"""A user's light, whatever its spelling: a light in words, a preset name or a light file.

This is what every command, job and the app call on a light the user gives (``--light``, a
preset picked in the app); the files alone are :func:`relightnet.sh.load_light_file`.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError
from ..sh.basis import sh_count
from ..sh.io import load_light_file
from .presets import preset_light, preset_names
from .words import is_light_words, light_from_words

__all__ = ["load_light"]


def load_light(path_or_name, lmax: int | None = None) -> torch.Tensor:
    """Load a light from a file, a preset name, a light in words, or an array.

    Args:
        path_or_name: ``.npz`` / ``.json`` (ours), ``.npy`` (Kanamori–Endo,
            BGR), ``.exr`` / ``.hdr`` environment map, a preset name, a light
            in words (:mod:`relightnet.light.words`), or an in-memory (K, 3) /
            (T, K, 3) tensor or array (validated and copied).
        lmax: SH order of the result. Environment maps, presets and lights in
            words are projected at this order (default 2). Stored coefficients are
            returned as stored when None, else truncated or zero-padded to it.

    Returns:
        (K, 3) or (T, K, 3) float32 linear RGB coefficients in the light frame.

    Raises:
        InputError: missing/unreadable file, NaN/Inf values, unknown preset
            (the message lists the presets); the message names the file.
        ShapeError: wrong number of coefficients or columns.
    """
    if lmax is not None:
        sh_count(lmax)
    if isinstance(path_or_name, (torch.Tensor, np.ndarray)):
        return load_light_file(path_or_name, lmax)
    if not isinstance(path_or_name, (str, os.PathLike)):
        raise InputError(f"light: expected a path, preset name or array, got {type(path_or_name).__name__}")
    if is_light_words(path_or_name) and not Path(path_or_name).exists():
        return light_from_words(path_or_name, 2 if lmax is None else lmax)
    path = Path(path_or_name)
    # A bare word (no suffix, no folder) is a preset name; presets win over same-named files.
    bare = isinstance(path_or_name, str) and not path.suffix.lower() and len(path.parts) == 1
    if bare and (not path.exists() or path_or_name in preset_names()):
        return preset_light(path_or_name, 2 if lmax is None else lmax)
    return load_light_file(path, lmax)
