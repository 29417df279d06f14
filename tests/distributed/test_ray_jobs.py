"""run_ray_jobs on a local Ray cluster: placement, a job no node can hold, per-job results in the driver."""

from relightnet.distributed.jobs import Job
from relightnet.distributed.ray_jobs import run_ray_jobs

PNG = b"\x89PNG\r\n\x1a\n"


def _job(index, args, out=None, cpus=1.0, gpus=0.0):
    return Job(index=index, command="light", args=tuple(args), out=out, cpus=cpus, gpus=gpus)


def test_jobs_run_as_ray_tasks_and_report_to_the_driver(ray_cluster, tmp_path):
    (tmp_path / "out").mkdir()
    jobs = [_job(0, ["show", "sunset", "--out", "out/s.png"], "out/s.png"),
            _job(2, ["show", "city", "--out", "out/c.png"], "out/c.png", cpus=64),
            _job(3, ["show", "city", "--out", "out/g.png"], "out/g.png", gpus=1)]
    results = {}
    run_ray_jobs(jobs, str(tmp_path), max_retries=1, on_done=lambda job, r: results.setdefault(job.index, r))
    assert sorted(results) == [0, 2, 3]
    assert results[0].status == "done" and results[0].attempts == 1 and results[0].error is None
    assert (tmp_path / "out" / "s.png").read_bytes()[:8] == PNG
    for i, need in ((2, "needs 64 CPU(s) and 0 GPU(s)"), (3, "needs 1 CPU(s) and 1 GPU(s)")):
        assert results[i].status == "failed" and results[i].attempts == 0  # refused at once, never queued
        assert results[i].error == f"{need} on one node; no node of the cluster has them"
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["s.png"]


def test_a_folder_the_nodes_do_not_see_fails_every_job(ray_cluster, tmp_path):
    results = []
    run_ray_jobs([_job(0, ["show", "sunset", "--out", "s.png"], "s.png")], str(tmp_path / "absent"), 0,
                 lambda job, r: results.append((job.index, r)))
    [(index, r)] = results
    assert index == 0 and r.status == "failed" and r.attempts == 0
    assert r.error.startswith(f"{tmp_path / 'absent'}: not found on node ") and "every node sees" in r.error
