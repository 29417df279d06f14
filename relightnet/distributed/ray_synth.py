"""``relightnet synth --ray``: one Ray task per shard, the manifest and progress bar on the driver.

Each task runs the shard function it is given (``relightnet synth`` gives
:func:`relightnet.data.pool.shard_task`, the same function as the local pool, so the bytes
are the same; this package sits below :mod:`relightnet.data` and does not import it) in a Ray
worker process that keeps its body assets between tasks, and writes its shard atomically into
the dataset folder, which must be a path every node sees. A task that raises, or whose worker
process or node dies, is run again up to ``max_retries`` times by Ray; one that still fails
comes back as a failure naming its shard.
Progress moves by whole shards as they are written (no actor: on a small machine another
Python process per run is a real cost).
"""

from __future__ import annotations

import logging
import socket
from pathlib import Path

from ..checks import InputError
from .cluster import import_ray, one_line
from .records import ShardFailure, ShardTask

__all__ = ["run_ray_shards"]

logger = logging.getLogger("relightnet.distributed")


def _ray_shard(shard_fn, task: ShardTask, fault: str | None) -> dict:
    """A Ray task: make and write one shard on whichever node runs it."""
    out_dir = Path(task.out_dir)
    if not out_dir.is_dir():
        raise InputError(f"{out_dir}: not found on node {socket.gethostname()}; the dataset folder must be "
                         "a path every node sees (a shared file system)")
    return shard_fn(task, None, fault)


def run_ray_shards(shard_fn, tasks: list, on_result, on_tick, cpus_per_task: float = 1, max_retries: int = 2,
                   fault: str | None = None) -> None:
    """Run shard tasks on the connected Ray cluster (see :func:`relightnet.distributed.connect`).

    Args:
        shard_fn: ``shard_fn(task, tick, fault) -> dict`` makes and writes one shard and returns its
            result (:func:`relightnet.data.pool.shard_task`); it must be importable on every node.
        tasks: the :class:`~relightnet.distributed.records.ShardTask` s.
        on_result: gets every finished shard's result (in finishing order), or its
            :class:`~relightnet.distributed.records.ShardFailure` once its retries are spent.
        on_tick: called with a shard's sample count when it is written (progress).
        cpus_per_task: CPUs Ray reserves for each task (the generator itself runs one torch thread).
        max_retries: Ray retries of a task that raised or whose process died.
        fault: the test-only fault hook's spec (:mod:`relightnet.data.fault_hook`), or None.
    """
    ray = import_ray()
    if not cpus_per_task > 0:
        raise InputError(f"--cpus-per-task: expected a number > 0, got {cpus_per_task}")
    run = ray.remote(_ray_shard).options(num_cpus=cpus_per_task, max_retries=int(max_retries),
                                         retry_exceptions=True)
    pending = {run.remote(shard_fn, t, fault): t for t in tasks}
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1, timeout=1.0)
            for ref in ready:
                task = pending.pop(ref)
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayError as e:
                    result = ShardFailure(task.split, task.index, one_line(e), max_retries + 1)
                else:
                    on_tick(result["count"])
                on_result(result)
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
