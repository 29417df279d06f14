"""Make a synthetic dataset folder: shards written by a process pool or a Ray cluster, a manifest, resumable.

A dataset folder holds ``{split}-{i:05d}.npz`` shards (:mod:`relightnet.data.shards`)
and ``manifest.json``::

    {"format": "relightnet-synth/1", "generator_version": "...", "config": {...},
     "complete": true, "fields": {"image": {"shape": [256, 256, 3], "dtype": "float32"}, ...},
     "splits": {"train": {"count": 64, "n_shards": 4,
                          "shards": [{"file": "train-00000.npz", "index": 0, "start": 0, "count": 16,
                                      "sha256": "...", "bytes": 123456}, ...]}, ...}}

The manifest is rewritten (atomically) as shards finish (at most once a second, and at
the end; a shard written but not listed yet is verified and listed on resume) and has no
timestamps, so an interrupted run that is run again ends with the same manifest and
the same shard bytes as an uninterrupted one — whatever the number of workers, local or
on a Ray cluster (:mod:`relightnet.distributed.ray_synth`): every sample is seeded by
(seed, split, index) and generated with one torch thread. Workers write shards (each
atomically, into a folder every worker sees); only the driver writes the manifest. A
shard that still fails after its retries is named, with its error, in :class:`ShardsFailed`.

With ``cfg.sequence_frames = T > 0`` every item is a clip from ``generate_sequence``:
a shard holds ``shard_size`` clips, each field gaining a frame axis (n, T, H, W, C).
"""

from __future__ import annotations

import contextlib
import json
import logging
import time
from pathlib import Path

from ..checks import InputError, RelightError
from ..distributed.records import ShardFailure, ShardTask
from ..io import atomic_write
from .config import SPLITS, SynthConfig
from .making import fields_of, make_and_write_shard, make_items, make_shard
from .shards import (
    FORMAT,
    MANIFEST_NAME,
    expected_fields,
    file_sha256,
    load_manifest,
    read_shard,
    shard_name,
    shard_plan,
)

__all__ = ["make_items", "make_shard", "make_and_write_shard", "run_synth", "ShardsFailed"]

logger = logging.getLogger("relightnet.data.synth")

#: The driver rewrites the manifest at most this often while shards come in (and at the end):
#: with hundreds of workers, one rewrite per shard would make the driver the bottleneck.
#: A shard written but not yet listed when the driver is killed is verified and listed on resume.
MANIFEST_EVERY_S = 1.0


class ShardsFailed(RelightError):
    """Shards that could not be made after their retries; the others were written and a rerun resumes.

    ``failures``: ``[(shard file name, one-line error), ...]``.
    """

    def __init__(self, out_dir, failures: list[tuple[str, str]], attempts: int):
        self.failures = failures
        named = "; ".join(f"{name}: {err}" for name, err in failures)
        super().__init__(f"{out_dir}: {len(failures)} shard(s) failed after {attempts} attempt(s) ({named}); "
                         "the other shards are written; run the same command again to retry")


def _write_manifest(out_dir: Path, manifest: dict) -> None:
    with atomic_write(out_dir / MANIFEST_NAME, "w") as f:
        f.write(json.dumps(manifest, indent=1, sort_keys=True) + "\n")


def _new_manifest(cfg: SynthConfig, version: str) -> dict:
    splits = {s: {"count": int(cfg.counts.get(s, 0)), "n_shards": len(shard_plan(cfg, s)), "shards": []}
              for s in SPLITS}
    return {"format": FORMAT, "generator_version": version, "config": cfg.to_dict(), "complete": False,
            "fields": {}, "splits": splits}


def _merge_existing(out_dir: Path, cfg: SynthConfig, version: str) -> dict:
    """A fresh manifest for ``cfg`` keeping the still-valid shard entries of an existing one.

    Raises:
        InputError: the existing dataset was made with another config or generator version,
            or ``cfg`` would shrink one of its splits.
    """
    new = _new_manifest(cfg, version)
    if not (out_dir / MANIFEST_NAME).exists():
        return new
    old = load_manifest(out_dir)
    a, b = dict(old.get("config", {})), cfg.to_dict()
    diffs = [f"{k}: {a.get(k)!r} there, {b.get(k)!r} now" for k in sorted(set(a) | set(b))
             if k != "counts" and a.get(k) != b.get(k)]
    if old.get("generator_version") != version:
        diffs.insert(0, f"generator_version: {old.get('generator_version')!r} there, {version!r} now")
    if diffs:
        raise InputError(f"{out_dir}: the dataset there was made with other settings ({'; '.join(diffs)}); "
                         "use another --out folder or the same settings to resume")
    for s in SPLITS:
        have = int(old["splits"].get(s, {}).get("count", 0))
        if have > new["splits"][s]["count"]:
            raise InputError(f"{out_dir}: {s} has {have} samples there; count {new['splits'][s]['count']} "
                             "would shrink it (counts may only grow); use another --out folder")
        plan = {(i, st, n) for i, st, n in shard_plan(cfg, s)}
        new["splits"][s]["shards"] = [e for e in old["splits"].get(s, {}).get("shards", [])
                                      if (e["index"], e["start"], e["count"]) in plan]
    new["fields"] = old.get("fields", {})
    return new


def _shard_ok(path: Path, cfg: SynthConfig, start: int, count: int) -> dict | None:
    """Load an unlisted shard file and return its fields if it is a complete, well-formed shard."""
    try:
        arrays = read_shard(path)
    except InputError:
        return None
    for name, (shape, dtype) in expected_fields(cfg).items():
        a = arrays.get(name)
        if a is None or a.shape != (count, *shape) or str(a.dtype) != dtype:
            return None
    meta = arrays.get("meta", [])
    if len(meta) != count or any(m.get("seed", {}).get("index", start + j) != start + j
                                 for j, m in enumerate(meta) if isinstance(m, dict)):
        return None
    return fields_of({k: v for k, v in arrays.items() if k != "meta"})


def _finished(out_dir: Path, manifest: dict, cfg: SynthConfig, split: str, index: int, start: int,
              count: int) -> bool:
    """Whether shard ``index`` is done (checksum verified), recovering unlisted complete files."""
    entries = manifest["splits"][split]["shards"]
    path = out_dir / shard_name(split, index)
    entry = next((e for e in entries if e["index"] == index), None)
    if entry is not None:
        if path.is_file() and path.stat().st_size == entry["bytes"] and file_sha256(path) == entry["sha256"]:
            return True
        logger.warning("%s: missing or checksum mismatch; making it again", path)
        entries.remove(entry)
        return False
    if path.is_file():
        fields = _shard_ok(path, cfg, start, count)
        if fields is not None:
            logger.info("%s: complete file not in the manifest; adding it", path)
            _add_entry(manifest, {"split": split, "index": index, "start": start, "count": count,
                                  "sha256": file_sha256(path), "bytes": path.stat().st_size, "fields": fields})
            return True
    return False


def _add_entry(manifest: dict, r: dict) -> None:
    """Record a finished shard ``r`` (split, index, start, count, sha256, bytes, fields)."""
    entries = manifest["splits"][r["split"]]["shards"]
    entries[:] = [e for e in entries if e["index"] != r["index"]]
    entries.append({"file": shard_name(r["split"], r["index"]), **{k: r[k] for k in
                    ("index", "start", "count", "sha256", "bytes")}})
    entries.sort(key=lambda e: e["index"])
    manifest["fields"] = r["fields"]
    manifest["complete"] = all(len(v["shards"]) == v["n_shards"] for v in manifest["splits"].values())


def _cleanup_temp(out_dir: Path) -> None:
    """Remove temporary files a killed run left behind (atomic writes never leave half files in place)."""
    for p in out_dir.glob(".*.tmp"):
        if p.name.startswith(f".{MANIFEST_NAME}.") or any(p.name.startswith(f".{s}-") for s in SPLITS):
            with contextlib.suppress(OSError):
                p.unlink()


def _run_here(tasks: list, body, max_retries: int, on_result, on_tick) -> None:
    """Run shard tasks in this process, each tried up to ``1 + max_retries`` times."""
    from ..distributed.cluster import one_line
    from .generate import prepare_assets

    body = prepare_assets() if body is None else body
    for t in tasks:
        for attempt in range(1, max_retries + 2):
            try:
                on_result(make_and_write_shard(SynthConfig.from_dict(t.config), t.split, t.index, t.out_dir,
                                               t.compression, body, lambda: on_tick(1)))
                break
            except Exception as e:  # noqa: BLE001 - reported with its shard, never lost
                logger.warning("%s: attempt %d failed: %s", shard_name(t.split, t.index), attempt, one_line(e))
                if attempt > max_retries:
                    on_result(ShardFailure(t.split, t.index, one_line(e), attempt))


def _dispatch(tasks: list, workers: int, ray, body, max_retries: int, on_result, on_tick) -> None:
    """Run shard tasks in this process (workers=0), on the local pool, or on Ray (``ray`` given)."""
    from .fault_hook import fault_spec
    from .pool import run_pool, shard_task

    fault = fault_spec()  # the test-only fault hook: None outside tests
    if ray is not None:
        from ..distributed.cluster import connect
        from ..distributed.ray_synth import run_ray_shards

        with connect(ray.address):
            run_ray_shards(shard_task, tasks, on_result, on_tick, cpus_per_task=ray.cpus_per_task,
                           max_retries=max_retries, fault=fault)
    elif workers == 0:
        _run_here(tasks, body, max_retries, on_result, on_tick)
    else:
        run_pool(tasks, workers, on_result, on_tick, max_retries=max_retries, fault=fault)


def _make_shards(out_dir: Path, cfg: SynthConfig, manifest: dict, todo: list, total: int, workers: int, ray, body,
                 max_retries: int, compression: str, progress: bool) -> None:
    """Dispatch the shards still to make (:func:`_dispatch`), listing each in the manifest as it
    comes in; raises :class:`ShardsFailed` naming those that still failed after their retries."""
    from tqdm import tqdm

    remaining = sum(t[3] for t in todo)
    bar = tqdm(total=total, initial=total - remaining, unit="sample", desc="synth", disable=not progress,
               smoothing=0.1, dynamic_ncols=True)
    failures = []

    def finished(r: dict | ShardFailure) -> None:
        if isinstance(r, ShardFailure):
            failures.append((shard_name(r.split, r.index), r.error))
            return
        _add_entry(manifest, r)
        if time.monotonic() - written[0] >= MANIFEST_EVERY_S:
            _write_manifest(out_dir, manifest)
            written[0] = time.monotonic()

    written = [time.monotonic()]
    tasks = [ShardTask(cfg.to_dict(), s, i, str(out_dir), compression) for s, i, _, _ in todo]
    try:
        _dispatch(tasks, int(workers), ray, body, int(max_retries), finished, bar.update)
    finally:
        bar.close()
        _write_manifest(out_dir, manifest)  # every shard written is listed, whatever happened
        _cleanup_temp(out_dir)  # every writer has stopped: no temporary file outlives the run
    if failures:
        raise ShardsFailed(out_dir, sorted(failures), int(max_retries) + 1)


def run_synth(out_dir, cfg: SynthConfig, workers: int = 1, splits=None, progress: bool = True,
              compression: str = "deflate", body=None, ray=None, max_retries: int = 2) -> dict:
    """Make every missing shard of a dataset folder, and its manifest.

    Args:
        out_dir: dataset folder (created if needed; its parent must exist; with ``ray``, a path
            every node of the cluster sees).
        cfg: generator config (counts, res, seed, shard size, ...).
        workers: generator processes, one shard per task (forkserver/spawn; each builds its body
            assets once and writes its shards); 0 runs in this process. The bytes written do not
            depend on it. Ignored with ``ray``.
        splits: which splits to make now (default: all with a non-zero count).
        progress: show a tqdm bar (samples/s).
        compression: shard compression, ``"deflate"`` or ``"store"``.
        body: with ``workers=0``, a prebuilt AnnyBody or ``SynthAssets`` to reuse (built if None).
        ray: a :class:`relightnet.distributed.RayOptions` to run one Ray task per shard on a
            cluster instead (needs the optional ``ray`` package); None: locally.
        max_retries: times a shard that raised, or whose worker process died (pool or Ray; or
            its Ray node), is tried again.

    Returns:
        The manifest (also in ``out_dir/manifest.json``).

    Raises:
        InputError: bad arguments, or ``out_dir`` holds a dataset made with another config.
        ShardsFailed: some shards still failed after their retries (the others are written and
            in the manifest; nothing half-written is left).
    """
    from .generate import GENERATOR_VERSION

    if not isinstance(cfg, SynthConfig):
        raise InputError(f"cfg: expected a SynthConfig, got {type(cfg).__name__}")
    for name, v in (("workers", workers), ("max_retries", max_retries)):
        if int(v) != v or v < 0:
            raise InputError(f"{name}: expected an integer >= 0, got {v!r}")
    splits = [s for s in SPLITS if cfg.counts.get(s, 0)] if splits is None else list(splits)
    bad = [s for s in splits if s not in SPLITS]
    if bad:
        raise InputError(f"splits: expected names from {SPLITS}, got {bad}")
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"{out_dir}: exists and is not a folder")
    if not out_dir.parent.is_dir():
        raise InputError(f"{out_dir}: parent folder {out_dir.parent} does not exist")
    manifest = _merge_existing(out_dir, cfg, GENERATOR_VERSION) if out_dir.is_dir() else _new_manifest(
        cfg, GENERATOR_VERSION)
    out_dir.mkdir(exist_ok=True)
    _cleanup_temp(out_dir)

    todo = []  # (split, shard index, start, count)
    for s in splits:
        for i, start, count in shard_plan(cfg, s):
            if not _finished(out_dir, manifest, cfg, s, i, start, count):
                todo.append((s, i, start, count))
    manifest["complete"] = all(len(v["shards"]) == v["n_shards"] for v in manifest["splits"].values())
    _write_manifest(out_dir, manifest)
    total = sum(cfg.counts.get(s, 0) for s in splits)
    remaining = sum(t[3] for t in todo)
    logger.info("%s: %d of %d shards to make (%d samples)", out_dir, len(todo),
                sum(len(shard_plan(cfg, s)) for s in splits), remaining)
    if not todo:
        return manifest

    _make_shards(out_dir, cfg, manifest, todo, total, workers, ray, body, max_retries, compression, progress)
    logger.info("%s: done (%s)", out_dir, "complete" if manifest["complete"] else "some splits still to make")
    return manifest
