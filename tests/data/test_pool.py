import dataclasses

import pytest

from relightnet.data import SynthConfig
from relightnet.data.fault_hook import FAULT_ENV
from relightnet.data.pool import LocalPool
from relightnet.data.shards import verify_dataset
from relightnet.data.synth import run_synth
from relightnet.distributed.records import ShardFailure, ShardTask

pytestmark = pytest.mark.slow  # process pools whose workers build the body assets and die on purpose

CFG = SynthConfig(res=32, n_dirs=16, shard_size=2, counts={"train": 4, "val": 0, "test": 0})


def _files(d):
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


def test_a_dying_worker_is_replaced_and_its_shard_retried(tmp_path, monkeypatch, anny_body):
    """The local pool's process making train-00001 exits mid-shard once: the shard is made again, same bytes."""
    ref = tmp_path / "ref"
    run_synth(ref, CFG, workers=0, progress=False, body=anny_body)
    marker = tmp_path / "died-once"
    monkeypatch.setenv(FAULT_ENV, f"train-00001.npz@{marker}")
    d = tmp_path / "ds"
    m = run_synth(d, CFG, workers=2, progress=False, max_retries=1)
    assert marker.exists() and m["complete"] and verify_dataset(d).ok
    assert _files(d) == _files(ref)


def test_a_shard_that_keeps_killing_its_worker_fails_alone(tmp_path):
    failures, done = [], []
    task = ShardTask(CFG.to_dict(), "train", 0, str(tmp_path), "store")
    with LocalPool(1, max_retries=0, fault="train-00000.npz") as pool:  # every attempt dies
        pool.run([task, dataclasses.replace(task, index=1)],
                 lambda r: (failures if isinstance(r, ShardFailure) else done).append(r), lambda n: None)
    assert [r["index"] for r in done] == [1] and (tmp_path / "train-00001.npz").is_file()
    assert failures == [ShardFailure("train", 0, "WorkerCrashedError: the worker process died (killed or out of "
                                     "memory) while making the shard", attempts=1)]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["train-00001.npz"]  # nothing half-written
