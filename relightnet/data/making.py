"""Making shards in this process: generate the samples (or clips) of a shard, single-threaded, and
write it. What the local pool's workers, Ray tasks and ``workers=0`` runs of
:func:`relightnet.data.synth.run_synth` all call (a module of its own so that the pool and the
driver import it without importing each other).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..checks import InputError
from ..threads import torch_threads
from .config import SynthConfig
from .shards import shard_name, shard_plan, stack_samples, write_shard

__all__ = ["make_items", "make_shard", "make_and_write_shard", "fields_of"]


def fields_of(arrays: dict) -> dict:
    """``{field: {"shape": per-item shape, "dtype"}}`` of stacked shard arrays (the manifest's ``fields``)."""
    return {k: {"shape": list(a.shape[1:]), "dtype": str(a.dtype)} for k, a in sorted(arrays.items()) if k != "meta"}


def _generate(cfg: SynthConfig, split: str, index: int, body):
    from .generate import generate_sample, generate_sequence

    if cfg.sequence_frames:
        return generate_sequence(cfg, split, index, cfg.sequence_frames, body=body)
    return generate_sample(cfg, split, index, body=body)


def make_items(cfg: SynthConfig, split: str, indices, body=None) -> list:
    """Generate samples (or clips) in this process, single-threaded as the workers do.

    ``body``: None, an AnnyBody or the generator's ``SynthAssets`` (reused across samples).
    """
    from .generate import prepare_assets

    body = body if body is not None else prepare_assets()
    with torch_threads(1):  # reductions then do not depend on the machine's core count
        if not cfg.sequence_frames:
            from .generate import generate_samples

            return generate_samples(cfg, split, [int(i) for i in indices], body)
        return [_generate(cfg, split, int(i), body) for i in indices]


def make_shard(cfg: SynthConfig, split: str, index: int, body=None) -> dict[str, np.ndarray]:
    """The arrays of shard ``index`` of ``split`` (as written by :func:`run_synth`)."""
    plan = shard_plan(cfg, split)
    if not 0 <= index < len(plan):
        raise InputError(f"shard index: {split} has {len(plan)} shards, got {index}")
    _, start, count = plan[index]
    return stack_samples(make_items(cfg, split, range(start, start + count), body))


def make_and_write_shard(cfg: SynthConfig, split: str, index: int, out_dir, compression: str = "deflate",
                         body=None, tick=None) -> dict:
    """Generate shard ``index`` of ``split`` and write it to ``out_dir`` (atomically).

    Args:
        tick: optional callable, called after every sample (progress).

    Returns:
        ``{"split", "index", "start", "count", "sha256", "bytes", "fields"}``.
    """
    from .generate import prepare_assets

    _, start, count = shard_plan(cfg, split)[index]
    body = body if body is not None else prepare_assets()
    samples = []
    with torch_threads(1):  # reductions then do not depend on the machine's core count
        if cfg.sequence_frames:
            for j in range(count):
                samples.append(_generate(cfg, split, start + j, body))
                if tick is not None:
                    tick()
        else:  # group by group: each person's PRT is computed once (cfg.prt_reuse)
            from .generate import generate_samples

            G = cfg.prt_reuse
            j = start
            while j < start + count:
                end = min((j // G + 1) * G, start + count)
                samples += generate_samples(cfg, split, range(j, end), body)
                for _ in range(end - j):
                    if tick is not None:
                        tick()
                j = end
    arrays = stack_samples(samples)
    del samples
    info = write_shard(Path(out_dir) / shard_name(split, index), arrays, compression=compression)
    return {"split": split, "index": index, "start": start, "count": count, **info, "fields": fields_of(arrays)}
