"""``relightnet synth --ray``: one Ray task per shard, the manifest and progress bar on the driver.

Each task runs :func:`relightnet.data.pool.shard_task` (the same function as the local pool,
so the bytes are the same) in a Ray worker process that keeps its body assets between
tasks, and writes its shard atomically into the dataset folder, which must be a path every
node sees. A task that raises, or whose worker process or node dies, is run again up to
``max_retries`` times by Ray; one that still fails comes back as a failure naming its shard.
Progress: every task counts its samples in a small actor that the driver polls.
"""

from __future__ import annotations

import logging
import socket
from pathlib import Path

from ..checks import InputError
from .cluster import import_ray, one_line

__all__ = ["run_ray_shards"]

logger = logging.getLogger("relightnet.distributed")


class _Progress:
    """Samples made so far by each shard's current attempt (a Ray actor on the cluster)."""

    def __init__(self):
        self.counts: dict = {}

    def start(self, key) -> None:
        self.counts[key] = 0

    def tick(self, key) -> None:
        self.counts[key] = self.counts.get(key, 0) + 1

    def total(self) -> int:
        return sum(self.counts.values())


def _ray_shard(task: tuple, fault: str | None, progress) -> dict:
    """A Ray task: make and write one shard on whichever node runs it."""
    from ..data.pool import shard_task

    out_dir = Path(task[3])
    if not out_dir.is_dir():
        raise InputError(f"{out_dir}: not found on node {socket.gethostname()}; the dataset folder must be "
                         "a path every node sees (a shared file system)")
    key = (task[1], task[2])
    progress.start.remote(key)
    return shard_task(task, lambda: progress.tick.remote(key), fault)


def run_ray_shards(tasks: list, on_result, on_tick, cpus_per_task: float = 1, max_retries: int = 2,
                   fault: str | None = None, poll_s: float = 0.25) -> None:
    """Run shard tasks on the connected Ray cluster (see :func:`relightnet.distributed.connect`).

    Args:
        tasks: ``(cfg_dict, split, index, out_dir, compression)`` tuples.
        on_result: gets every finished shard's result (in finishing order), or a failure
            ``{"split", "index", "error"}`` once its retries are spent.
        on_tick: called with the number of samples made since the last call (progress).
        cpus_per_task: CPUs Ray reserves for each task (the generator itself runs one torch thread).
        max_retries: Ray retries of a task that raised or whose process died.
        fault: the fault-hook spec (:mod:`relightnet.data.pool`), or None.
    """
    ray = import_ray()
    if not cpus_per_task > 0:
        raise InputError(f"--cpus-per-task: expected a number > 0, got {cpus_per_task}")
    progress = ray.remote(_Progress).options(num_cpus=0).remote()
    run = ray.remote(_ray_shard).options(num_cpus=cpus_per_task, max_retries=int(max_retries),
                                         retry_exceptions=True)
    pending = {run.remote(t, fault, progress): t for t in tasks}
    seen = 0
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1, timeout=poll_s)
            for ref in ready:
                task = pending.pop(ref)
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayError as e:
                    result = {"split": task[1], "index": task[2], "error": one_line(e)}
                on_result(result)
            total = ray.get(progress.total.remote())
            if total > seen:  # a retried shard starts its count again: the bar never goes back
                on_tick(total - seen)
                seen = total
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
        ray.kill(progress)
