"""Light files: save and load SH lights (docs/design.md, "File contracts").

Formats, chosen by the file extension:

- ``.npz`` (ours): ``sh`` (K, 3) float32, or a sequence (T, K, 3); ``lmax`` (int);
  ``frame = "light"``; ``units = "linear radiance"``. Columns are linear RGB.
- ``.json`` (ours): ``{"sh": [[r, g, b], ...] (or T such lists), "lmax", "frame", "units"}``.
- a light *sequence* file (every command that writes lights over time, read by every command
  that takes a light): our ``.npz`` with ``sh`` (T, K, 3), the light of each frame, plus named
  side arrays about the same frames — ``raw`` (T, K, 3) estimates before smoothing, ``outliers``
  and ``switches`` (T,) bool, ``evidence_M`` (T, 3, K, K), ... — or single values
  (``smoothing``). :func:`save_light_sequence` / :func:`load_light_sequence`; :func:`load_light_file`
  reads such a file as its (T, K, 3) ``sh``.
- ``.npy``: a Kanamori–Endo (2018) light, exactly (9, 3) with **BGR** columns;
  converted to/from RGB here. Only single order-2 lights fit this format.
- ``.exr`` / ``.hdr`` (load only): a lat-long environment map, projected to SH.

A preset name (``studio``, ``sunset``, ...) or a light in words (``key:az=-40,el=30 + ambient:0.2``)
is not a file: :func:`relightnet.light.load_light` takes those, and files through :func:`load_light_file`.

Every loaded light is validated (finite values, K = (lmax+1)²) and returned as a
float32 RGB tensor; errors name the file. The commands also check a light the user gives against
physics (:func:`check_light_physics`): a light adds light, so its irradiance may dip below zero
only a little (SH ringing) and stays within what float32 shading carries; arbitrary coefficients
(research, tests) load as they are.
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, ShapeError, sh_order_from_count
from .basis import sh_count

__all__ = ["LIGHT_SUFFIXES", "MAX_IRRADIANCE", "save_light", "load_light_file", "check_light_physics", "resize_sh",
           "save_light_sequence", "load_light_sequence"]

logger = logging.getLogger(__name__)

#: Largest irradiance (linear units; the presets' is about 1 to 3) a light may have anywhere: past
#: it, shading a photo in float32 overflows or saturates every pixel. Physical HDR units stay below.
MAX_IRRADIANCE = 1e6
#: Irradiance counts as negative below this fraction of the light's peak: the order-2 ringing of one
#: directional source dips to about -3.7% of its peak behind it, which is not an error.
NEGATIVE_DEPTH = 0.05
#: Share of the sphere whose irradiance may be negative in some channel before a warning and before
#: a refusal (most of it: no scene has that).
NEGATIVE_WARN, NEGATIVE_REFUSE = 0.05, 0.5


def check_light_physics(sh: torch.Tensor, name: str = "light") -> torch.Tensor:
    """Refuse a light no scene has: irradiance above :data:`MAX_IRRADIANCE`, or negative (below
    :data:`NEGATIVE_DEPTH` of its peak) over more than half of the sphere in some channel; warn when
    more than a few percent of it is.

    Args:
        sh: (K, 3) light or (T, K, 3) light sequence (linear RGB, light frame).
        name: what to call it in messages (the file or the words).

    Returns:
        ``sh``, unchanged.

    Raises:
        InputError: naming ``name`` (and the frame of a sequence) and what was found.
    """
    from .metrics import irradiance_samples

    e = irradiance_samples(sh)  # (..., D, 3) float64 over the sphere
    peak = float(e.abs().max())
    if not peak <= MAX_IRRADIANCE:
        raise InputError(f"light {name}: its irradiance reaches {peak:.3g}; expected at most {MAX_IRRADIANCE:.0e} "
                         "(are the coefficients in linear radiance?)")
    scale = e.abs().amax((-2, -1), keepdim=True)  # each light's own peak
    negative = (e < -NEGATIVE_DEPTH * scale).double().mean(-2).reshape(-1)  # (T * 3,) share per channel
    worst = int(negative.argmax())
    share, channel = float(negative[worst]), "RGB"[worst % 3]
    where = f"{name} (frame {worst // 3})" if sh.dim() == 3 else name
    if share > NEGATIVE_REFUSE:
        raise InputError(f"light {where}: its {channel} irradiance is negative over {100 * share:.0f}% of the "
                         "sphere; a light adds light (expected it positive nearly everywhere)")
    if share > NEGATIVE_WARN:
        logger.warning("light %s: its %s irradiance is negative over %.0f%% of the sphere; those directions shade "
                       "black", where, channel, 100 * share)
    return sh

#: Suffixes :func:`save_light` writes; :func:`load_light_file` also reads ``.exr`` and ``.hdr``.
LIGHT_SUFFIXES = (".npz", ".json", ".npy")
_ENVMAP_SUFFIXES = (".exr", ".hdr")
_FRAME, _UNITS = "light", "linear radiance"
#: Most bytes a light file's ``sh`` (with its metadata) may hold: 64 MiB is a (T, 9, 3) float64
#: sequence of 310,000 frames (86 minutes at 60 fps); a light from a stranger cannot ask for more.
MAX_LIGHT_BYTES = 64 << 20
#: Most bytes of a light sequence's side arrays together (``raw``, ``evidence_M``, ...).
MAX_SIDE_BYTES = 512 << 20
#: The arrays of a light .npz itself; a sequence file's side arrays take other names.
_OWN = ("sh", "lmax", "frame", "units")


def resize_sh(sh: torch.Tensor, lmax: int) -> torch.Tensor:
    """Change the SH order of lights: drop higher bands or pad them with zeros.

    Dropping bands is the L2-best band-limited approximation; padding keeps the
    same function.

    Args:
        sh: (..., K, 3) coefficients.
        lmax: target order.

    Returns:
        (..., K', 3) with K' = (lmax+1)².
    """
    k_new = sh_count(lmax)
    k = sh.shape[-2]
    if k_new <= k:
        return sh[..., :k_new, :].clone()
    pad = sh.new_zeros(*sh.shape[:-2], k_new - k, sh.shape[-1])
    return torch.cat([sh, pad], dim=-2)


def _validate(sh, where: str) -> torch.Tensor:
    """Shape (K,3)|(T,K,3), valid K, finite; returns float32. Errors start with ``where``."""
    if not isinstance(sh, torch.Tensor):
        sh = np.asarray(sh)
        if sh.dtype.kind not in "biuf":
            raise InputError(f"{where}: expected real coefficients, got dtype {sh.dtype}")
        sh = torch.as_tensor(sh.astype(sh.dtype.newbyteorder("=")))
    if sh.dim() not in (2, 3) or sh.shape[-1] != 3:
        raise ShapeError(f"{where}: expected a light (K, 3) or a sequence (T, K, 3), got {tuple(sh.shape)}")
    sh_order_from_count(sh.shape[-2], where)
    if not (sh.is_floating_point() or sh.dtype in (torch.int32, torch.int64)):
        raise InputError(f"{where}: expected real coefficients, got dtype {sh.dtype}")
    sh = sh.detach().to(device="cpu", dtype=torch.float32)
    if not bool(torch.isfinite(sh).all()):
        raise InputError(f"{where}: coefficients contain NaN or Inf")
    return sh


def save_light(path: str | os.PathLike, sh) -> Path:
    """Write a light or light sequence atomically; format by extension.

    Args:
        path: ``.npz`` or ``.json`` (any K, single or sequence), or ``.npy``
            (Kanamori–Endo: one order-2 light, written as (9, 3) BGR).
        sh: (K, 3) or (T, K, 3) linear RGB coefficients in the light frame.

    Returns:
        The path written.

    Raises:
        ShapeError: bad shape, or a ``.npy`` that is not a single (9, 3) light.
        InputError: NaN/Inf values or an unsupported extension.
    """
    from ..io.atomic import atomic_write

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in LIGHT_SUFFIXES:
        raise InputError(f"{path}: unsupported light file type; expected one of {', '.join(LIGHT_SUFFIXES)}")
    sh = _validate(sh, "sh")
    lmax = sh_order_from_count(sh.shape[-2])
    arr = sh.numpy()
    if suffix == ".npy":
        if tuple(arr.shape) != (9, 3):
            raise ShapeError(
                f"{path}: a Kanamori-Endo .npy holds one order-2 light (9, 3); got {tuple(arr.shape)}; "
                "use .npz or .json"
            )
        with atomic_write(path) as f:
            np.save(f, np.ascontiguousarray(arr[:, ::-1]))
    elif suffix == ".npz":
        with atomic_write(path) as f:
            np.savez(f, sh=arr, lmax=np.int64(lmax), frame=np.str_(_FRAME), units=np.str_(_UNITS))
    else:
        # One coefficient row (or one frame) per line: readable and diff-friendly.
        rows = ",\n  ".join(json.dumps(r) for r in arr.tolist())
        head = json.dumps({"lmax": lmax, "frame": _FRAME, "units": _UNITS})[:-1]
        with atomic_write(path, "w") as f:
            f.write(f'{head}, "sh": [\n  {rows}\n]}}\n')
    return path


def _check_meta(path: Path, lmax_stored, frame, units, k: int) -> None:
    if lmax_stored is not None:
        try:
            lm = int(lmax_stored)
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"{path}: 'lmax' must be an integer, got {lmax_stored!r}") from None
        if sh_count(max(lm, 0)) != k or lm < 0:
            raise ShapeError(f"{path}: 'lmax' = {lm} needs K = {(lm + 1) ** 2} coefficients, file has {k}")
    if frame is not None and str(frame) != _FRAME:
        raise InputError(f"{path}: light is in frame {str(frame)!r}; expected {_FRAME!r}")
    if units is not None and str(units) != _UNITS:
        raise InputError(f"{path}: light units are {str(units)!r}; expected {_UNITS!r}")


def _scalar_meta(arrays: dict, key: str, path: Path):
    """A metadata entry (``lmax``, ``frame``, ``units``) of a light .npz: one value or None."""
    if key not in arrays:
        return None
    a = arrays[key]
    if a.size != 1:
        raise InputError(f"{path}: {key!r} must be a single value, got shape {tuple(a.shape)}")
    return a.reshape(()).item()


def _read_npz(path: Path) -> torch.Tensor:
    from ..io.arrays import read_npz

    z = read_npz(path, "light .npz", ("sh", "lmax", "frame", "units"), max_bytes=MAX_LIGHT_BYTES)
    if "sh" not in z:
        raise InputError(f"{path}: no 'sh' array in the .npz (has {', '.join(sorted(z)) or 'nothing else'})")
    meta = {k: _scalar_meta(z, k, path) for k in ("lmax", "frame", "units")}
    sh = _validate(z["sh"], str(path))
    _check_meta(path, meta["lmax"], meta["frame"], meta["units"], sh.shape[-2])
    return sh


def _read_json(path: Path) -> torch.Tensor:
    from ..io.documents import read_document

    doc = read_document(path, "light .json", yaml_ok=False)
    if not isinstance(doc, dict) or "sh" not in doc:
        raise InputError(f"{path}: expected a JSON object with an 'sh' list")
    try:
        arr = np.asarray(doc["sh"], dtype=np.float64)
    except (TypeError, ValueError, RecursionError):
        raise ShapeError(f"{path}: 'sh' must be a K×3 (or T×K×3) list of numbers") from None
    sh = _validate(arr, str(path))
    _check_meta(path, doc.get("lmax"), doc.get("frame"), doc.get("units"), sh.shape[-2])
    return sh


def _read_npy(path: Path) -> torch.Tensor:
    from ..io.arrays import read_npy

    arr = read_npy(path, "Kanamori-Endo light .npy", max_bytes=1 << 16)
    if tuple(arr.shape) != (9, 3):
        raise ShapeError(f"{path}: a Kanamori-Endo light .npy must be (9, 3) BGR, got {tuple(arr.shape)}")
    if not np.issubdtype(arr.dtype, np.number) or arr.dtype.kind == "c":
        raise InputError(f"{path}: expected real coefficients, got dtype {arr.dtype}")
    return _validate(np.ascontiguousarray(arr[:, ::-1]).astype(np.float64), str(path))


def load_light_file(path, lmax: int | None = None) -> torch.Tensor:
    """Load a light from a file or an array (a preset name or a light in words is
    :func:`relightnet.light.load_light`).

    Args:
        path: ``.npz`` / ``.json`` (ours), ``.npy`` (Kanamori–Endo, BGR), ``.exr`` / ``.hdr``
            environment map, or an in-memory (K, 3) / (T, K, 3) tensor or array (validated and copied).
        lmax: SH order of the result. Environment maps are projected at this order (default 2).
            Stored coefficients are returned as stored when None, else truncated or zero-padded to it.

    Returns:
        (K, 3) or (T, K, 3) float32 linear RGB coefficients in the light frame.

    Raises:
        InputError: missing/unreadable file, NaN/Inf values; the message names the file.
        ShapeError: wrong number of coefficients or columns.
    """
    if lmax is not None:
        sh_count(lmax)
    if isinstance(path, (torch.Tensor, np.ndarray)):
        sh = _validate(path, "light").clone()
        return sh if lmax is None else resize_sh(sh, lmax)
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"light: expected a path, preset name or array, got {type(path).__name__}")
    path = Path(path)
    suffix = path.suffix.lower()
    known = LIGHT_SUFFIXES + _ENVMAP_SUFFIXES
    if not path.exists():
        raise InputError(f"{path}: no such light file")
    if path.is_dir():
        raise InputError(f"{path}: is a folder, not a light file")
    if suffix in _ENVMAP_SUFFIXES:
        from ..io.envmap import read_envmap
        from .projection import project_envmap

        return project_envmap(read_envmap(path), 2 if lmax is None else lmax).float()
    readers = {".npz": _read_npz, ".json": _read_json, ".npy": _read_npy}
    if suffix not in readers:
        raise InputError(f"{path}: unsupported light file type; expected one of {', '.join(known)} or a preset")
    sh = readers[suffix](path)
    logger.debug("loaded light %s: %s", path, tuple(sh.shape))
    return sh if lmax is None else resize_sh(sh, lmax)


def _side_array(name: str, value, t: int, where: str) -> np.ndarray:
    """A side array of a light sequence: T rows (or one value), numbers, booleans or text."""
    if isinstance(value, torch.Tensor):
        value = value.detach().cpu().numpy()
    arr = np.asarray(value)
    if arr.dtype.kind not in "biufU":
        raise InputError(f"{where}: side array {name!r} has dtype {arr.dtype}; expected numbers, booleans or text")
    if arr.ndim and arr.shape[0] != t:
        raise ShapeError(f"{where}: side array {name!r} has {arr.shape[0]} rows; expected one per frame ({t}) "
                         "or a single value")
    return arr


def save_light_sequence(path: str | os.PathLike, sh, **side) -> Path:
    """Write a light sequence with side arrays about its frames, atomically, as our ``.npz``.

    Args:
        path: the ``.npz`` to write.
        sh: (T, K, 3) linear RGB, the light of each frame (what a renderer uses).
        **side: named arrays about the same frames: (T, ...) each (``raw`` (T, K, 3),
            ``outliers`` (T,) bool, ...) or a single value (``smoothing="hermite"``).
            Tensors are copied to numpy. Not the names ``sh``, ``lmax``, ``frame``, ``units``.

    Returns:
        The path written; :func:`load_light_file` reads it as the (T, K, 3) sequence.

    Raises:
        ShapeError: ``sh`` not (T, K, 3), or a side array without T rows.
        InputError: not ``.npz``, a reserved name, NaN/Inf in ``sh``, a non-numeric side array.
    """
    from ..io.atomic import atomic_write

    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise InputError(f"{path}: a light sequence with side arrays is written as .npz")
    sh = _validate(sh, "sh")
    if sh.dim() != 3:
        raise ShapeError(f"{path}: expected a light sequence (T, K, 3), got {tuple(sh.shape)}")
    clash = sorted(set(side) & set(_OWN))
    if clash:
        raise InputError(f"{path}: side array names {clash} are the light's own; choose other names")
    arrays = {k: _side_array(k, v, sh.shape[0], str(path)) for k, v in side.items()}
    with atomic_write(path) as f:
        np.savez_compressed(f, sh=sh.numpy(), lmax=np.int64(sh_order_from_count(sh.shape[-2])),
                            frame=np.str_(_FRAME), units=np.str_(_UNITS), **arrays)
    return path


def load_light_sequence(path: str | os.PathLike, names=None) -> tuple[torch.Tensor, dict[str, np.ndarray]]:
    """Read a light sequence and its side arrays (see :func:`save_light_sequence`).

    Args:
        path: a light sequence ``.npz`` (ours; side arrays optional) or ``.json`` (no side arrays).
        names: the side arrays wanted (those the file has are returned); None: all of them.

    Returns:
        (sh (T, K, 3) float32, {name: array with T rows or one value}).

    Raises:
        InputError / ShapeError: not a light sequence, bad values, or a side array without T rows;
            the message names the file.
    """
    path = Path(path)
    sh = load_light_file(path)
    if sh.dim() != 3:
        raise ShapeError(f"{path}: expected a light sequence (T, K, 3), got one light {tuple(sh.shape)}")
    if path.suffix.lower() != ".npz":
        return sh, {}
    from ..io.arrays import read_npz, read_npz_names

    wanted = [n for n in (read_npz_names(path) if names is None else names) if n not in _OWN]
    side = read_npz(path, "light sequence .npz", wanted, max_bytes=MAX_SIDE_BYTES) if wanted else {}
    return sh, {k: _side_array(k, v, sh.shape[0], str(path)) for k, v in side.items()}
