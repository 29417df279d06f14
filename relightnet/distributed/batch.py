"""``relightnet batch``: run a jobs file locally or on a Ray cluster, resumable, with a summary.

Every job runs as its own ``relightnet`` subprocess (a crash, a leak or a hung library
takes down that job only) with its resources: locally, as many at once as the CPUs (and
GPUs) allow, in file order; on Ray, one task per job with ``num_cpus``/``num_gpus``. The
semantics are the same: a bad entry fails alone with its one-line reason, a crashed job is
retried, a job whose output already exists complete is skipped (outputs are written
atomically, so an existing ``--out`` file is complete; an ``--out`` folder counts as
complete when the previous summary says that job was done), and the summary
``JOBS.summary.json`` (beside the jobs file) is rewritten atomically as jobs end (at most
once every :data:`SUMMARY_INTERVAL` seconds, and at the end), so a killed driver resumes by
running the same command again. Each job's output (stdout and
stderr, the last 20,000 characters) goes to ``JOBS.logs/NNN.log``.
"""

from __future__ import annotations

import json
import logging
import math
import os
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from pathlib import Path

from ..io import atomic_write
from .cluster import default_workers
from .jobs import Job, execute_job, load_jobs
from .records import JOB_STATUSES, JobResult

__all__ = ["run_batch", "summary_path", "summary_entry", "write_summary", "SUMMARY_FORMAT"]

logger = logging.getLogger("relightnet.distributed")

SUMMARY_FORMAT = "relightnet-batch/1"
#: Least seconds between two rewrites of the summary while jobs run (thousands of jobs that
#: end at once, e.g. bad entries, would otherwise rewrite it thousands of times).
SUMMARY_INTERVAL = 2.0


def summary_path(jobs_file) -> Path:
    """``JOBS.summary.json`` beside ``JOBS.yaml``."""
    p = Path(jobs_file)
    return p.with_name(f"{p.stem}.summary.json")


def _logs_dir(jobs_file) -> Path:
    p = Path(jobs_file)
    return p.with_name(f"{p.stem}.logs")


def _previous(path: Path) -> dict:
    """{(command, args): record} of the jobs a previous summary says were done or skipped."""
    try:
        old = json.loads(path.read_text())
        return {(r["command"], tuple(r["args"])): r for r in old.get("jobs", [])
                if r.get("status") in ("done", "skipped")}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return {}


def _complete(job: Job, cwd: Path, previous: dict) -> bool:
    out = cwd / job.out
    if out.is_file():
        return True
    return out.is_dir() and (job.command, job.args) in previous


def _local_gpus() -> int:
    import torch

    return torch.cuda.device_count() if torch.cuda.is_available() else 0


def run_local(jobs: list[Job], cwd: str, max_retries: int, on_done) -> None:
    """Run jobs on this machine, as many at once as their CPUs and GPUs fit, in file order.

    A job asking for more CPUs than the machine has runs alone with all of them; one asking
    for more GPUs than there are fails. ``on_done(job, result)`` is called in this thread.
    """
    cpus = default_workers()
    gpus = _local_gpus() if any(j.gpus for j in jobs) else 0
    free_cpus, free_gpus = float(cpus), list(range(gpus))
    pending, running = list(jobs), {}
    with ThreadPoolExecutor(max_workers=max(1, len(jobs))) as pool:
        while pending or running:
            for job in list(pending):
                need_c, need_g = min(job.cpus, cpus), math.ceil(job.gpus)
                if need_g > gpus:
                    pending.remove(job)
                    on_done(job, JobResult.failed(f"needs {job.gpus:g} GPU(s); this machine has {gpus}"))
                    continue
                if need_c > free_cpus + 1e-9 or need_g > len(free_gpus):
                    continue
                ids, free_gpus = free_gpus[:need_g], free_gpus[need_g:]
                free_cpus -= need_c
                env = {"OMP_NUM_THREADS": str(max(1, int(need_c)))}
                if gpus:
                    env["CUDA_VISIBLE_DEVICES"] = ",".join(map(str, ids))
                running[pool.submit(execute_job, job, cwd, max_retries, env)] = (job, need_c, ids)
                pending.remove(job)
            if not running:
                continue
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for fut in done:
                job, c, ids = running.pop(fut)
                free_cpus += c
                free_gpus = sorted(free_gpus + ids)
                on_done(job, fut.result())


def summary_entry(job: Job, result: JobResult | None = None, log: str | None = None) -> dict:
    """A job's entry in the summary (:data:`SUMMARY_FORMAT`): the job as its file gave it
    (:meth:`~relightnet.distributed.jobs.Job.record`), then how it went (``pending`` without a result)."""
    r = result if result is not None else JobResult("pending")
    return {**job.record(), "status": r.status, "error": r.error, "seconds": round(r.seconds, 3),
            "attempts": r.attempts, "log": log}


def write_summary(path: Path, jobs_file, runner: str, entries: list[dict]) -> dict:
    """Write the summary atomically, the one writer of :data:`SUMMARY_FORMAT`: ``{"format", "jobs_file",
    "runner", "counts": {done, skipped, failed, pending}, "jobs": [summary_entry, ...]}``; returns it."""
    summary = {"format": SUMMARY_FORMAT, "jobs_file": str(jobs_file), "runner": runner,
               "counts": {s: sum(e["status"] == s for e in entries) for s in JOB_STATUSES}, "jobs": entries}
    with atomic_write(path, "w") as f:
        f.write(json.dumps(summary, indent=1) + "\n")
    return summary


def run_batch(jobs_file, commands, ray=None, max_retries: int = 1, progress: bool = True) -> dict:
    """Run every job of a jobs file that is not complete yet (module docstring).

    Args:
        jobs_file: the YAML/JSON jobs file (:mod:`relightnet.distributed.jobs`).
        commands: the CLI's command table, {name: parser}, that the jobs are checked against
            (:func:`relightnet.cli.command_table`).
        ray: a :class:`relightnet.distributed.RayOptions` (its ``address``) to run on a Ray
            cluster; None: on this machine.
        max_retries: times a crashed job is run again (bad input is not retried).
        progress: show a tqdm bar over the jobs.

    Returns:
        The summary (also written to ``JOBS.summary.json``): ``{"format", "jobs_file", "runner",
        "counts": {done, skipped, failed, pending}, "jobs": [{index, command, args, out,
        resources, status, error, seconds, attempts, log}]}``.

    Raises:
        InputError: the jobs file is unreadable or has no ``jobs`` list.
    """
    from tqdm import tqdm

    jobs = load_jobs(jobs_file, commands)
    cwd = Path.cwd()
    spath, logs = summary_path(jobs_file), _logs_dir(jobs_file)
    previous = _previous(spath)
    entries = [summary_entry(j) for j in jobs]
    runner = "ray" if ray else "local"
    summary = {}

    last = [-math.inf]

    def write(force: bool = True) -> None:
        if not force and time.monotonic() - last[0] < SUMMARY_INTERVAL:
            return
        summary.update(write_summary(spath, jobs_file, runner, entries))
        last[0] = time.monotonic()

    bar = tqdm(total=len(jobs), unit="job", desc="batch", disable=not progress, dynamic_ncols=True)

    def done(job: Job, result: JobResult) -> None:
        log = None
        if result.output:
            logs.mkdir(exist_ok=True)
            log = str(logs / f"{job.index:03d}.log")
            with atomic_write(log, "w") as f:
                f.write(f"$ relightnet {job.command} {' '.join(job.args)}\n{result.output.rstrip()}\n")
        entries[job.index] = summary_entry(job, result, log)
        logger.info("job %d (%s): %s%s", job.index, " ".join([job.command, *([job.out] if job.out else [])]),
                    result.status, f": {result.error}" if result.error else "")
        bar.update(1)
        write(force=False)

    todo = []
    for job in jobs:
        if job.error is not None:
            done(job, JobResult.failed(job.error))
        elif _complete(job, cwd, previous):
            done(job, JobResult("skipped"))
        else:
            todo.append(job)
    write()
    try:
        if todo and ray is not None:
            from .cluster import connect
            from .ray_jobs import run_ray_jobs

            with connect(ray.address):
                run_ray_jobs(todo, os.fspath(cwd), max_retries, done)
        elif todo:
            run_local(todo, os.fspath(cwd), max_retries, done)
    finally:
        bar.close()
        write()
    return summary
