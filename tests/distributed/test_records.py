"""relightnet.distributed.records: the typed records of shard tasks and batch jobs."""

import dataclasses
import json
import pickle

import pytest

from relightnet.distributed.batch import SUMMARY_FORMAT, summary_entry, write_summary
from relightnet.distributed.jobs import Job
from relightnet.distributed.records import JOB_STATUSES, JobResult, ShardFailure, ShardTask


def test_records_are_frozen_named_and_pickle():
    task = ShardTask({"res": 32}, "train", 3, "/data", "store")
    assert task.key == ("train", 3) and pickle.loads(pickle.dumps(task)) == task
    with pytest.raises(dataclasses.FrozenInstanceError):
        task.index = 4
    fail = ShardFailure("val", 0, "OSError: disk full", attempts=2)
    assert pickle.loads(pickle.dumps(fail)) == fail


def test_job_results_have_a_known_status():
    assert JobResult.failed("x.mp4: not found") == JobResult("failed", "x.mp4: not found", 0.0, 0, "")
    assert JobResult("skipped").error is None
    with pytest.raises(ValueError, match="status: expected one of done, skipped, failed, pending"):
        JobResult("ok")


def test_the_summary_has_one_writer(tmp_path):
    jobs = [Job(0, "light", ("show", "city", "--out", "a.png"), "a.png"),
            Job(1, "light", ("show", "x", "--out", "b.png"), "b.png")]
    entries = [summary_entry(jobs[0], JobResult("done", None, 1.23456, 1, "log text"), "logs/000.log"),
               summary_entry(jobs[1])]
    s = write_summary(tmp_path / "j.summary.json", "j.yaml", "local", entries)
    assert s["format"] == SUMMARY_FORMAT and s["counts"] == {"done": 1, "skipped": 0, "failed": 0, "pending": 1}
    assert list(s["counts"]) == list(JOB_STATUSES)
    assert entries[0] == {"index": 0, "command": "light", "args": ["show", "city", "--out", "a.png"], "out": "a.png",
                          "resources": {"cpus": 1.0, "gpus": 0.0}, "status": "done", "error": None, "seconds": 1.235,
                          "attempts": 1, "log": "logs/000.log"}
    assert entries[1]["status"] == "pending" and entries[1]["log"] is None
    assert json.loads((tmp_path / "j.summary.json").read_text()) == s
