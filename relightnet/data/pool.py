"""Running shard tasks: the task every executor runs, and the local process pool.

A shard task is a :class:`~relightnet.distributed.records.ShardTask`: make shard ``index`` of
``split`` and write it (atomically) into ``out_dir``. :func:`shard_task` runs one in the
calling process — a pool worker, a Ray worker (:mod:`relightnet.distributed.ray_synth`) or
the driver — with body assets built once per process; the driver alone writes the manifest.
A shard that still fails after its retries comes back as a
:class:`~relightnet.distributed.records.ShardFailure`. The ``fault`` argument is the spec of the
test-only fault hook (:mod:`relightnet.data.fault_hook`), None outside tests.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import multiprocessing as mp
import queue
import threading
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from ..distributed.records import ShardFailure, ShardTask
from .config import SynthConfig
from .shards import shard_name

__all__ = ["shard_task", "worker_assets", "LocalPool", "run_pool"]

logger = logging.getLogger("relightnet.data.synth")

_WORKER: dict = {}


def worker_assets():
    """This process's generator assets (the body model and its precomputations), built on first use."""
    if "body" not in _WORKER:
        from .generate import prepare_assets

        _WORKER["body"] = prepare_assets()
    return _WORKER["body"]


def shard_task(task: ShardTask, tick=None, fault: str | None = None) -> dict:
    """Make and write one shard in this process (raises on failure).

    Args:
        task: which shard, with the generator's configuration.
        tick: optional callable, called after every sample.
        fault: the test-only fault hook's spec (:mod:`relightnet.data.fault_hook`), or None.

    Returns:
        The shard's manifest entry ``{"split", "index", "start", "count", "sha256", "bytes", "fields"}``.
    """
    from .making import make_and_write_shard

    if fault is not None:
        from .fault_hook import faulty_tick

        tick = faulty_tick(fault, shard_name(task.split, task.index), tick)
    return make_and_write_shard(SynthConfig.from_dict(task.config), task.split, task.index, task.out_dir,
                                task.compression, worker_assets(), tick)


def _worker_init(ticks, fault, max_retries) -> None:
    import torch

    # a pool worker's initialiser owns its process: one thread for good (the pool runs a process a core)
    torch.set_num_threads(1)
    with contextlib.suppress(RuntimeError):
        torch.set_num_interop_threads(1)
    worker_assets()
    _WORKER.update(ticks=ticks, fault=fault, max_retries=max_retries)


def _worker_task(task: ShardTask) -> dict | ShardFailure:
    """A shard task with in-process retries: its manifest entry, or its failure."""
    from ..distributed.cluster import one_line

    ticks, attempts = _WORKER["ticks"], 1 + _WORKER["max_retries"]
    for attempt in range(1, attempts + 1):
        try:
            return shard_task(task, lambda: ticks.put(1), _WORKER["fault"])
        except Exception as e:  # noqa: BLE001 - reported with its shard, never lost
            error = one_line(e)
            logger.warning("%s: attempt %d of %d failed: %s", shard_name(task.split, task.index), attempt, attempts,
                           error)
    return ShardFailure(task.split, task.index, error, attempts)


class LocalPool:
    """A local process pool of shard workers, usable for several runs (a context manager).

    Workers start with forkserver (the generator preloaded; never a fork of a threaded
    process), else spawn; each builds its body assets once (and keeps its memos of env maps
    and clothing regions across runs) and runs torch single-threaded. A task that raises is
    tried again in its worker up to ``max_retries`` times; when a worker process dies (killed,
    out of memory), the shards that were in flight are charged one attempt each and run
    again on fresh workers, up to ``max_retries`` times, like a Ray task.

    Args:
        workers: processes.
        max_retries: retries of a task that raised, and of a task whose process died.
        fault: the test-only fault hook's spec handed to the workers (:mod:`relightnet.data.fault_hook`), or None.
    """

    def __init__(self, workers: int, max_retries: int = 0, fault: str | None = None):
        if "forkserver" in mp.get_all_start_methods():
            self._ctx = mp.get_context("forkserver")
            self._ctx.set_forkserver_preload(["relightnet.data.generate"])
        else:  # pragma: no cover - not POSIX
            self._ctx = mp.get_context("spawn")
        self._ticks = self._ctx.Queue()
        self._workers, self._max_retries, self._fault = int(workers), int(max_retries), fault
        self._pool = self._start()

    def _start(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(self._workers, mp_context=self._ctx, initializer=_worker_init,
                                   initargs=(self._ticks, self._fault, self._max_retries))

    def _drain(self, on_tick, stop: threading.Event) -> None:
        while True:
            try:
                self._ticks.get(timeout=0.05)
            except queue.Empty:
                if stop.is_set():
                    return
                continue
            on_tick(1)

    def run(self, tasks: list, on_result, on_tick) -> None:
        """Run :class:`~relightnet.distributed.records.ShardTask` s, at most one per worker at a time.

        ``on_result`` gets every finished shard's manifest entry (any order), or its
        :class:`~relightnet.distributed.records.ShardFailure`; ``on_tick`` is called with 1 after every sample.
        """
        stop = threading.Event()
        thread = threading.Thread(target=self._drain, args=(on_tick, stop), daemon=True)
        thread.start()
        todo, running, deaths = collections.deque(tasks), {}, collections.Counter()
        try:
            while todo or running:
                while todo and len(running) < self._workers:
                    task = todo.popleft()
                    running[self._pool.submit(_worker_task, task)] = task
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                if any(isinstance(f.exception(), BrokenProcessPool) for f in done):
                    self._pool.shutdown(wait=True, cancel_futures=True)  # every task in flight died with it
                    self._pool = self._start()
                    for task in running.values():
                        deaths[task.key] += 1
                        name = shard_name(task.split, task.index)
                        if deaths[task.key] > self._max_retries:
                            on_result(ShardFailure(task.split, task.index, "WorkerCrashedError: the worker process "
                                                   "died (killed or out of memory) while making the shard",
                                                   deaths[task.key]))
                        else:
                            logger.warning("%s: a worker process died while making it; trying again", name)
                            todo.appendleft(task)
                    running.clear()
                    continue
                for f in done:
                    running.pop(f)
                    on_result(f.result())
        finally:
            stop.set()
            thread.join()

    def close(self, kill: bool = False) -> None:
        """Stop the workers: after their current shard, or at once with ``kill`` (an interrupted run)."""
        if kill:  # ProcessPoolExecutor has no public way to stop running work before Python 3.14
            for p in list(getattr(self._pool, "_processes", {}).values()):
                p.kill()
        self._pool.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> LocalPool:
        return self

    def __exit__(self, exc_type, *exc) -> None:
        self.close(kill=exc_type is not None)


def run_pool(tasks: list, workers: int, on_result, on_tick, max_retries: int = 0, fault: str | None = None) -> None:
    """Run shard tasks on a new :class:`LocalPool` of ``min(workers, len(tasks))`` processes, then close it."""
    with LocalPool(min(workers, len(tasks)), max_retries, fault) as pool:
        pool.run(tasks, on_result, on_tick)
