"""The captured person's file: ``NAME.avatar.npz``, arrays only, read without pickle.

========================  ================  ===================================================
key                       shape, dtype      meaning
========================  ================  ===================================================
``format``                () str            ``"relightnet-avatar"``
``version``               () int32          :data:`VERSION`
``body_model``            () str            ``"anny"`` (the UV layout and the vertex order)
``num_verts``             () int32          V of the body the offsets belong to
``texture``               (S, S, 3) float16 linear RGB albedo in the body's UV layout, row 0 = v = 1
``confidence``            (S, S) float16    sum of the frames' sample weights (0: never seen)
``filled``                (S, S) int8       0 seen, 1 from the mirror image, 2 inpainted
``offsets``               (V,) float32      metres along the posed normal (:func:`apply_offsets`)
``phenotype``             (6,) float32      the fitted body's phenotype (``PHENOTYPES`` order)
``seen_share``            () float32        share of the body's surface texels seen
``frames``                () int32          frames the texture was fused from
========================  ================  ===================================================

A file of another format, version or body, a missing key or a wrong shape is a one-line
:class:`~relightnet.checks.InputError` naming the file and the key.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..body import PHENOTYPES
from ..checks import InputError, check_shape
from ..io.arrays import read_npz
from ..io.atomic import atomic_write

__all__ = ["VERSION", "AVATAR_SUFFIX", "MAX_OFFSET", "CapturedAvatar", "save_avatar", "load_avatar"]

#: The file format's version; a reader refuses any other.
VERSION = 1
#: What an avatar file's name ends with.
AVATAR_SUFFIX = ".avatar.npz"
_FORMAT = "relightnet-avatar"
#: Largest texture side a file may hold (a 4096² texture is 100 MB of float16).
_MAX_SIZE = 4096
#: Largest offset a file may hold, metres (a coat or a skirt stands a few centimetres off the body).
MAX_OFFSET = 0.5


@dataclass(frozen=True, eq=False)
class CapturedAvatar:
    """A captured person (the file's arrays as tensors; module docstring).

    Attributes:
        texture: (S, S, 3) float32 linear albedo. confidence: (S, S) float32. filled: (S, S) int8.
        offsets: (V,) float32. phenotype: (6,) float32. seen_share: float. frames: int.
        body_model: ``"anny"``.
    """

    texture: torch.Tensor
    confidence: torch.Tensor
    filled: torch.Tensor
    offsets: torch.Tensor
    phenotype: torch.Tensor
    seen_share: float
    frames: int
    body_model: str = "anny"

    def __post_init__(self) -> None:
        d = check_shape(self.texture, ["S", "S", 3], name="texture")
        check_shape(self.confidence, [d["S"], d["S"]], name="confidence")
        check_shape(self.filled, [d["S"], d["S"]], name="filled")
        check_shape(self.offsets, ["V"], name="offsets")
        check_shape(self.phenotype, [6], name="phenotype")


def save_avatar(path: str | Path, avatar: CapturedAvatar) -> Path:
    """Write ``avatar`` to ``path`` (ending in :data:`AVATAR_SUFFIX`) atomically."""
    path = Path(path)
    if not path.name.endswith(AVATAR_SUFFIX):
        raise InputError(f"{path}: expected a file name ending in {AVATAR_SUFFIX}")
    arrays = {
        "format": np.array(_FORMAT), "version": np.int32(VERSION), "body_model": np.array(avatar.body_model),
        "num_verts": np.int32(avatar.offsets.numel()),
        "texture": avatar.texture.numpy().astype(np.float16),
        "confidence": avatar.confidence.numpy().astype(np.float16),
        "filled": avatar.filled.numpy().astype(np.int8), "offsets": avatar.offsets.numpy().astype(np.float32),
        "phenotype": avatar.phenotype.numpy().astype(np.float32),
        "seen_share": np.float32(avatar.seen_share), "frames": np.int32(avatar.frames),
    }
    with atomic_write(path) as f:
        np.savez_compressed(f, **arrays)
    return path


def _scalar(raw: dict, key: str, name: str, kind: type):
    if key not in raw:
        raise InputError(f"{name}: missing key {key!r} (not a relightnet avatar file?)")
    a = np.asarray(raw[key])
    if a.shape != ():
        raise InputError(f"{name}: key {key!r}: expected a single value, got shape {a.shape}")
    try:
        return kind(a.item())
    except (TypeError, ValueError):
        raise InputError(f"{name}: key {key!r}: expected a {kind.__name__}, got {a.dtype}") from None


def _array(raw: dict, key: str, name: str, shape: tuple, finite: bool = True) -> np.ndarray:
    if key not in raw:
        raise InputError(f"{name}: missing key {key!r} (not a relightnet avatar file?)")
    a = np.asarray(raw[key])
    if a.shape != shape or a.dtype.kind not in "fiu":
        raise InputError(f"{name}: key {key!r}: expected a numeric array of shape {shape}, got {a.dtype} {a.shape}")
    if finite and not np.isfinite(a).all():
        raise InputError(f"{name}: key {key!r}: contains NaN or Inf values")
    return a


def _f32(a: np.ndarray) -> torch.Tensor:
    return torch.from_numpy(np.ascontiguousarray(a, dtype=np.float32))


def load_avatar(path: str | Path, num_verts: int | None = None) -> CapturedAvatar:
    """Read an avatar file; ``num_verts`` (the body's V) is checked when given.

    Raises:
        InputError: one line naming the file and the key (module docstring).
    """
    path = Path(path)
    name = path.name
    raw = read_npz(path, "avatar file")
    if _scalar(raw, "format", name, str) != _FORMAT:
        raise InputError(f"{name}: key 'format': expected {_FORMAT!r} (not a relightnet avatar file)")
    if (v := _scalar(raw, "version", name, int)) != VERSION:
        raise InputError(f"{name}: key 'version': version {v}, this relightnet reads version {VERSION}")
    if (b := _scalar(raw, "body_model", name, str)) != "anny":
        raise InputError(f"{name}: key 'body_model': expected 'anny', got {b!r}")
    nv = _scalar(raw, "num_verts", name, int)
    if num_verts is not None and nv != num_verts:
        raise InputError(f"{name}: key 'num_verts': captured on a body of {nv} vertices, this body has {num_verts}")
    tex = np.asarray(raw.get("texture", np.zeros(0)))
    s = tex.shape[0] if tex.ndim == 3 else -1
    if not 8 <= s <= _MAX_SIZE:
        raise InputError(f"{name}: key 'texture': expected (S, S, 3) with 8 <= S <= {_MAX_SIZE}, got {tex.shape}")
    offsets = _array(raw, "offsets", name, (nv,))
    if np.abs(offsets).max(initial=0.0) > MAX_OFFSET:
        raise InputError(f"{name}: key 'offsets': an offset of {np.abs(offsets).max():.2f} m (at most {MAX_OFFSET} m)")
    phen = _array(raw, "phenotype", name, (6,))
    for j, (n, (lo, hi, _)) in enumerate(PHENOTYPES.items()):
        if not lo - 1e-6 <= phen[j] <= hi + 1e-6:
            raise InputError(f"{name}: key 'phenotype': {n} = {phen[j]:.3g} is outside [{lo:.3g}, {hi:.3g}]")
    return CapturedAvatar(
        texture=_f32(_array(raw, "texture", name, (s, s, 3))).clamp_(0, 1),
        confidence=_f32(_array(raw, "confidence", name, (s, s))),
        filled=torch.from_numpy(_array(raw, "filled", name, (s, s)).astype(np.int8)),
        offsets=_f32(offsets), phenotype=_f32(phen),
        seen_share=_scalar(raw, "seen_share", name, float), frames=_scalar(raw, "frames", name, int))
