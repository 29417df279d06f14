"""``relightnet batch --ray``: one Ray task per job, with the job's CPUs and GPUs.

The task is :func:`relightnet.distributed.jobs.execute_job`, the same function the local
runner calls, so a job runs as the same ``relightnet`` subprocess with the same retries;
Ray adds the placement (``num_cpus``/``num_gpus``; it sets ``CUDA_VISIBLE_DEVICES`` and
``OMP_NUM_THREADS`` for the job) and runs a task again when its node or worker dies.
"""

from __future__ import annotations

from .cluster import import_ray, one_line
from .jobs import Job, execute_job
from .records import JobResult

__all__ = ["run_ray_jobs"]


def _node_resources(ray) -> list[dict]:
    return [n.get("Resources", {}) for n in ray.nodes() if n.get("Alive")]


def run_ray_jobs(jobs: list[Job], cwd: str, max_retries: int, on_done) -> None:
    """Run jobs on the connected Ray cluster; ``on_done(job, result)`` is called in this thread.

    A job no node has the CPUs and GPUs for fails at once (Ray would wait for such a node forever).
    ``cwd`` (where relative paths point) must be a folder every node sees.
    """
    ray = import_ray()
    nodes = _node_resources(ray)
    run = ray.remote(execute_job)
    pending = {}
    for job in jobs:
        if not any(r.get("CPU", 0) >= job.cpus and r.get("GPU", 0) >= job.gpus for r in nodes):
            on_done(job, JobResult.failed(f"needs {job.cpus:g} CPU(s) and {job.gpus:g} GPU(s) on one node; no node "
                                          "of the cluster has them"))
            continue
        ref = run.options(num_cpus=job.cpus, num_gpus=job.gpus, max_retries=int(max_retries),
                          retry_exceptions=False).remote(job, cwd, max_retries)
        pending[ref] = job
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                job = pending.pop(ref)
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayError as e:
                    result = JobResult.failed(one_line(e))
                on_done(job, result)
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
