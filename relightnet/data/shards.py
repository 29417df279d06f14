"""Dataset shards: deterministic ``.npz`` files of stacked samples, their layout, the manifest, verification.

A shard holds ``n`` consecutive samples of one split. Every sample field is stacked on
axis 0 (``image`` (n, H, W, 3), ``transport`` (n, H, W, K), ``light`` (n, K, 3), ...;
clips of a sequence dataset add a frame axis: (n, T, H, W, 3)), channels-last as the
generator makes them. The per-sample metadata is the ``meta`` entry: an (n,) unicode
array of JSON objects (``np.load`` reads it without pickle).

Shards are byte-for-byte reproducible: :func:`write_shard` writes the zip itself with
fixed entry dates (1980-01-01), fixed permissions, sorted entry order and one
compression setting, so the same arrays always give the same file and sha256. Files are
written atomically (temporary file + rename). With ``"deflate"`` the ``background`` entry
is stored: its float noise deflates to ~0.9 of its size at a third of the shard's writing time.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..checks import InputError
from ..io import atomic_write
from ..io.arrays import read_npz, read_npz_names
from .config import SPLITS, SynthConfig

__all__ = [
    "MANIFEST_NAME",
    "FORMAT",
    "load_manifest",
    "dataset_config",
    "VerifyReport",
    "verify_dataset",
    "SAMPLE_FIELDS",
    "shard_name",
    "shard_plan",
    "expected_fields",
    "write_shard",
    "read_shard",
    "read_shard_meta",
    "stack_samples",
    "file_sha256",
]

#: Per-sample fields the generator makes: name → (shape, dtype). ``H``/``W`` are
#: ``cfg.res``, ``K`` is ``cfg.n_coeffs``; sequence datasets add ``T`` after the sample axis.
SAMPLE_FIELDS = {
    "image": (("H", "W", 3), "float32"),
    "image_srgb": (("H", "W", 3), "uint8"),
    "mask": (("H", "W"), "float32"),
    "albedo": (("H", "W", 3), "float32"),
    "transport": (("H", "W", "K"), "float32"),
    "transport_unoccluded": (("H", "W", "K"), "float32"),
    "light": (("K", 3), "float32"),
    "normals": (("H", "W", 3), "float32"),
    "depth": (("H", "W"), "float32"),
    "parts": (("H", "W"), "uint8"),
    "background": (("H", "W", 3), "float32"),
    "image_composite": (("H", "W", 3), "uint8"),
}

MANIFEST_NAME = "manifest.json"
FORMAT = "relightnet-synth/1"
_DATE = (1980, 1, 1, 0, 0, 0)
_COMPRESSION = {"deflate": (zipfile.ZIP_DEFLATED, 1), "store": (zipfile.ZIP_STORED, None)}
#: Entries stored even with ``"deflate"``: deflate barely shrinks them (module docstring).
_STORED = frozenset({"background"})


def shard_name(split: str, index: int) -> str:
    """File name of shard ``index`` of ``split``: ``train-00003.npz``."""
    if split not in SPLITS:
        raise InputError(f"split: expected one of {SPLITS}, got {split!r}")
    return f"{split}-{int(index):05d}.npz"


def shard_plan(cfg: SynthConfig, split: str) -> list[tuple[int, int, int]]:
    """The shards of a split: ``[(shard_index, first_sample, n_samples), ...]``.

    Shard ``i`` holds samples ``i·shard_size ..`` up to the split's count (the last one may be short).
    """
    if split not in SPLITS:
        raise InputError(f"split: expected one of {SPLITS}, got {split!r}")
    n, size = int(cfg.counts.get(split, 0)), cfg.shard_size
    return [(i, s, min(size, n - s)) for i, s in enumerate(range(0, n, size))]


def expected_fields(cfg: SynthConfig) -> dict[str, tuple[tuple[int, ...], str]]:
    """Per-sample shape (without the stacking axis; with T for sequences) and dtype of every field."""
    sizes = {"H": cfg.res, "W": cfg.res, "K": cfg.n_coeffs}
    lead = (cfg.sequence_frames,) if cfg.sequence_frames else ()
    return {
        name: (lead + tuple(sizes.get(d, d) for d in shape), dtype)
        for name, (shape, dtype) in SAMPLE_FIELDS.items()
    }


def stack_samples(samples: list) -> dict[str, np.ndarray]:
    """Stack generator samples (objects with ``arrays`` and ``meta``) into shard arrays.

    Returns:
        {field: (n, ...) array} plus ``meta``: (n,) unicode JSON strings.
    """
    if not samples:
        raise InputError("stack_samples: expected at least one sample")
    names = list(samples[0].arrays)
    for s in samples[1:]:
        if list(s.arrays) != names:
            raise InputError(f"stack_samples: samples have different fields: {names} vs {list(s.arrays)}")
    out = {k: np.stack([np.asarray(s.arrays[k]) for s in samples]) for k in names}
    if "meta" in out:
        raise InputError("stack_samples: 'meta' is reserved for the sample metadata")
    out["meta"] = np.array([json.dumps(s.meta, sort_keys=True, separators=(",", ":")) for s in samples])
    return out


def _write_entry(zf: zipfile.ZipFile, info: zipfile.ZipInfo, arr: np.ndarray, level) -> None:
    """Write ``arr`` as the ``.npy`` entry ``info``: the same bytes as ``writestr(info, npy bytes)``, but the
    array's buffer goes to the compressor as it is (no copies of a whole shard field)."""
    arr = np.ascontiguousarray(arr)
    buf, d = io.BytesIO(), np.lib.format.header_data_from_array_1_0(arr)
    try:  # the header version np.save picks: 1.0 unless it is too long
        np.lib.format.write_array_header_1_0(buf, d)
    except ValueError:
        buf = io.BytesIO()
        np.lib.format.write_array_header_2_0(buf, d)
    head = buf.getvalue()
    body = memoryview(arr.reshape(-1).view(np.uint8))
    info.file_size = len(head) + len(body)  # as writestr sets it (it decides the zip64 extra field)
    info._compresslevel = level  # what writestr(..., compresslevel=level) sets
    with zf.open(info, mode="w") as dest:
        dest.write(head)
        dest.write(body)


def write_shard(path, arrays: dict[str, np.ndarray], compression: str = "deflate") -> dict:
    """Write arrays as a reproducible ``.npz`` (readable by ``np.load``), atomically.

    Args:
        path: destination ``.npz``; its folder must exist.
        arrays: {name: array}; no object arrays. Entries are written in sorted name order.
        compression: ``"deflate"`` (zlib level 1; ``background`` is stored) or ``"store"``.

    Returns:
        ``{"sha256": hex digest, "bytes": file size}`` of the written file.
    """
    if compression not in _COMPRESSION:
        raise InputError(f"compression: expected one of {sorted(_COMPRESSION)}, got {compression!r}")
    method, level = _COMPRESSION[compression]
    path = Path(path)
    with atomic_write(path) as f:
        with zipfile.ZipFile(f, "w", compression=method, compresslevel=level, allowZip64=True) as zf:
            for name in sorted(arrays):
                arr = np.asarray(arrays[name])
                if arr.dtype.hasobject:
                    raise InputError(f"{name}: object arrays cannot go in a shard")
                m, lv = (zipfile.ZIP_STORED, None) if name in _STORED else (method, level)
                info = zipfile.ZipInfo(f"{name}.npy", date_time=_DATE)
                info.compress_type, info.create_system = m, 3
                info.external_attr = 0o644 << 16
                _write_entry(zf, info, arr, lv)
    return {"sha256": file_sha256(path), "bytes": path.stat().st_size}


def read_shard(path, fields=None) -> dict[str, np.ndarray]:
    """Load a shard's arrays (all, or only ``fields``; ``meta`` comes back as a list of dicts).

    Raises:
        InputError: missing or unreadable file, or a requested field it lacks.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: shard not found")
    out = read_npz(path, "shard", fields)
    if fields is not None:
        missing = [n for n in fields if n not in out]
        if missing:
            have = sorted(read_npz_names(path))
            raise InputError(f"{path}: shard has no field(s) {missing}; it has {have}")
    if "meta" in out:
        meta = out["meta"]
        if meta.ndim != 1 or meta.dtype.kind not in "US":
            raise InputError(f"{path}: meta: expected (n,) JSON strings, got {meta.dtype}{list(meta.shape)}")
        try:
            out["meta"] = [json.loads(str(m)) for m in meta]
        except (ValueError, RecursionError) as e:
            raise InputError(f"{path}: meta is not JSON ({type(e).__name__}: {e})") from None
    return out


def read_shard_meta(path) -> list[dict]:
    """The per-sample metadata of a shard (a list of dicts)."""
    return read_shard(path, ["meta"])["meta"]


def file_sha256(path, chunk: int = 1 << 22) -> str:
    """sha256 hex digest of a file."""
    h = hashlib.sha256()
    with open(os.fspath(path), "rb") as f:
        while block := f.read(chunk):
            h.update(block)
    return h.hexdigest()


def load_manifest(out_dir) -> dict:
    """Read ``out_dir/manifest.json``.

    Raises:
        InputError: the folder or manifest is missing or not a relightnet dataset manifest.
    """
    out_dir = Path(out_dir)
    if not out_dir.is_dir():
        raise InputError(f"{out_dir}: dataset folder not found")
    path = out_dir / MANIFEST_NAME
    if not path.is_file():
        raise InputError(f"{path}: no manifest (not a dataset folder made by 'relightnet synth')")
    from ..io.documents import read_document

    m = read_document(path, "dataset manifest", yaml_ok=False)
    if not isinstance(m, dict) or m.get("format") != FORMAT:
        raise InputError(f"{path}: expected a manifest of format {FORMAT!r}")
    _check_manifest(m, path)
    return m


def _nonneg_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 10**12


def _check_manifest(m: dict, path: Path) -> None:
    """The structure the readers rely on: a config mapping, and per split its counts and shard entries
    (``file`` exactly the shard's own name: a manifest cannot point outside its folder)."""
    if not isinstance(m.get("config"), dict):
        raise InputError(f"{path}: 'config' is not a mapping")
    splits = m.get("splits")
    if not isinstance(splits, dict) or set(splits) - set(SPLITS):
        raise InputError(f"{path}: 'splits' must map {list(SPLITS)} to their shards")
    if not isinstance(m.get("fields", {}), dict):
        raise InputError(f"{path}: 'fields' is not a mapping")
    for split, info in splits.items():
        where = f"{path}: splits.{split}"
        if not isinstance(info, dict) or not all(_nonneg_int(info.get(k)) for k in ("count", "n_shards")) \
                or not isinstance(info.get("shards"), list):
            raise InputError(f"{where}: expected count, n_shards (integers) and a shards list")
        for e in info["shards"]:
            if not isinstance(e, dict) or not all(_nonneg_int(e.get(k)) for k in ("index", "start", "count")):
                raise InputError(f"{where}: a shard entry without integer index, start and count")
            if e.get("file") != shard_name(split, e["index"]):
                raise InputError(f"{where}: shard {e['index']} names file {e.get('file')!r}, expected "
                                 f"{shard_name(split, e['index'])!r}")


def dataset_config(manifest: dict) -> SynthConfig:
    """The :class:`SynthConfig` a manifest records."""
    return SynthConfig.from_dict(manifest["config"])


@dataclass(frozen=True)
class VerifyReport:
    """What :func:`verify_dataset` found: ``problems`` (one line each; empty when all is well)."""

    problems: tuple
    n_shards: int
    counts: dict

    @property
    def ok(self) -> bool:
        return not self.problems


def verify_dataset(out_dir) -> VerifyReport:
    """Check a dataset folder against its manifest and config.

    Every shard listed must exist with its size and sha256; every planned shard must be
    listed; every field must have shape (n, *per-sample shape from the config: res, K, T)
    and the expected dtype; the ``meta`` entry must hold n JSON objects; the samples must
    add up to the split counts; no unlisted shard files.

    Returns:
        A :class:`VerifyReport`; a missing or unreadable manifest is reported as a problem.
    """
    out_dir = Path(out_dir)
    problems: list[str] = []
    try:
        manifest = load_manifest(out_dir)
        cfg = dataset_config(manifest)
    except (InputError, KeyError, TypeError) as e:
        return VerifyReport((str(e) if isinstance(e, InputError) else f"{out_dir}: bad manifest ({e})",), 0, {})
    expected = expected_fields(cfg)
    listed, n_shards, counts = set(), 0, {}
    for split in SPLITS:
        info = manifest.get("splits", {}).get(split, {})
        entries = {e.get("index"): e for e in info.get("shards", [])}
        counts[split] = 0
        for index, start, count in shard_plan(cfg, split):
            name = shard_name(split, index)
            listed.add(name)
            e = entries.get(index)
            path = out_dir / name
            if e is None:
                problems.append(f"{path}: not made yet (run 'relightnet synth' again with the same settings)")
                continue
            if (e.get("start"), e.get("count")) != (start, count):
                problems.append(f"{path}: manifest says samples {e.get('start')}+{e.get('count')}, "
                                f"config says {start}+{count}")
                continue
            if not path.is_file():
                problems.append(f"{path}: missing")
                continue
            if path.stat().st_size != e.get("bytes"):
                problems.append(f"{path}: {path.stat().st_size} bytes, manifest says {e.get('bytes')}")
                continue
            if file_sha256(path) != e.get("sha256"):
                problems.append(f"{path}: sha256 mismatch (corrupted or changed)")
                continue
            try:
                arrays = read_shard(path)
            except InputError as err:
                problems.append(str(err))
                continue
            for field, (shape, dtype) in expected.items():
                a = arrays.get(field)
                if a is None:
                    problems.append(f"{path}: field {field!r} missing")
                elif a.shape != (count, *shape) or str(a.dtype) != dtype:
                    problems.append(f"{path}: {field} is {a.dtype}{list(a.shape)}, expected {dtype}{[count, *shape]}")
            for field, a in arrays.items():
                if field not in expected and len(a) != count:
                    problems.append(f"{path}: {field} has {len(a)} entries, expected {count}")
            n_shards += 1
            counts[split] += count
        said = info.get("count", 0)
        if said != cfg.counts.get(split, 0):
            problems.append(f"{out_dir / MANIFEST_NAME}: {split} count {said}, config says {cfg.counts.get(split, 0)}")
    for path in sorted(out_dir.glob("*.npz")):
        if path.name not in listed:
            problems.append(f"{path}: shard file not in the manifest")
    return VerifyReport(tuple(problems), n_shards, counts)
