import json
import os
import signal
import subprocess
import sys
import time

import pytest

from relightnet.cli import command_table
from relightnet.distributed import RayOptions
from relightnet.distributed.batch import run_batch

GOOD = "- {command: light, args: [show, sunset, --out, out/sunset.png]}\n"
BAD = "- {command: light, args: [show, missing.npz, --out, out/bad.png]}\n"  # unreadable input
PNG = b"\x89PNG\r\n\x1a\n"


def _batch(*args):
    return [sys.executable, "-m", "relightnet.cli", "-q", "batch", "jobs.yaml", *args]


def _summary(folder):
    return json.loads((folder / "jobs.summary.json").read_text())


@pytest.mark.slow
def test_killed_driver_resumes_and_a_bad_job_fails_alone(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "jobs.yaml").write_text(
        "jobs:\n- {command: light, args: [show, city, --out, out/first.png], resources: {cpus: 2}}\n"  # runs alone
        + BAD + GOOD + "- {command: light, args: [show, night, --out, out/gpu.png], resources: {gpus: 8}}\n")
    first = tmp_path / "out" / "first.png"
    proc = subprocess.Popen(_batch(), cwd=tmp_path, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 600  # a safety net only: the kill comes when the output appears
        while time.monotonic() < deadline and proc.poll() is None and not first.exists():
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGKILL)  # the driver and its jobs
    finally:
        proc.wait()
    assert first.read_bytes()[:8] == PNG and not (tmp_path / "out" / "sunset.png").exists()
    stamp = os.stat(first).st_mtime_ns

    r = subprocess.run(_batch(), cwd=tmp_path, capture_output=True, text=True)
    assert r.returncode == 1, r.stderr  # a job failed
    s = _summary(tmp_path)
    assert s["counts"] == {"done": 1, "skipped": 1, "failed": 2, "pending": 0} and s["runner"] == "local"
    done_before, bad, good, gpu = s["jobs"]
    assert done_before["status"] == "skipped" and os.stat(first).st_mtime_ns == stamp  # not redone
    assert bad["status"] == "failed" and bad["error"] == "InputError: missing.npz: no such light file"
    assert bad["attempts"] == 1  # bad input is not retried
    assert "relightnet light: InputError: missing.npz" in (tmp_path / bad["log"]).read_text()
    assert good["status"] == "done" and good["error"] is None and good["seconds"] > 0
    assert gpu["status"] == "failed" and gpu["error"].startswith("needs 8 GPU(s); this machine has ")
    assert (tmp_path / "out" / "sunset.png").read_bytes()[:8] == PNG
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["first.png", "sunset.png"]  # nothing else
    lines = r.stdout.splitlines()
    assert lines[0].split() == ["job", "command", "status", "seconds", "output", "or", "error"]
    assert lines[1].split() == ["0", "light", "skipped", "0.0", "out/first.png"]
    assert lines[2].split()[:3] == ["1", "light", "failed"] and lines[2].endswith("missing.npz: no such light file")
    assert lines[3].split()[:3] == ["2", "light", "done"] and lines[3].endswith("out/sunset.png")
    assert "1 done, 1 skipped, 2 failed" in lines
    assert not list(tmp_path.rglob(".*.tmp"))


def test_one_bad_one_good_job_on_ray(ray_cluster, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "out").mkdir()
    (tmp_path / "jobs.yaml").write_text("jobs:\n" + BAD + GOOD + "- {command: light, args: [show, city, --out, "
                                        "out/c.png], resources: {cpus: 64}}\n")
    s = run_batch(tmp_path / "jobs.yaml", command_table(), ray=RayOptions(), progress=False)
    assert s == _summary(tmp_path) and s["runner"] == "ray"
    assert [j["status"] for j in s["jobs"]] == ["failed", "done", "failed"]
    assert s["jobs"][0]["error"] == "InputError: missing.npz: no such light file"
    assert s["jobs"][2]["error"] == "needs 64 CPU(s) and 0 GPU(s) on one node; no node of the cluster has them"
    assert (tmp_path / "out" / "sunset.png").read_bytes()[:8] == PNG
    # Run again: the finished job is skipped, the bad one fails again, nothing is redone.
    s = run_batch(tmp_path / "jobs.yaml", command_table(), ray=RayOptions(), progress=False)
    assert [j["status"] for j in s["jobs"]] == ["failed", "skipped", "failed"]
