import os
from pathlib import Path

import pytest

from relightnet import cli
from relightnet.data import SynthConfig
from relightnet.data.fault_hook import FAULT_ENV
from relightnet.data.shards import load_manifest, verify_dataset
from relightnet.data.synth import ShardsFailed, run_synth
from relightnet.distributed import RayOptions

CFG = SynthConfig(res=32, n_dirs=16, shard_size=2, counts={"train": 4, "val": 1, "test": 0})


def _files(d: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


@pytest.fixture(scope="module")
def ref(tmp_path_factory, anny_body):
    """The dataset made in this process (no Ray)."""
    d = tmp_path_factory.mktemp("ref") / "ds"
    run_synth(d, CFG, workers=0, progress=False, body=anny_body)
    return d


def test_ray_shards_match_local(ray_cluster, ref, tmp_path):
    d = tmp_path / "ds"
    m = run_synth(d, CFG, progress=False, ray=RayOptions(cpus_per_task=1))
    assert m["complete"] and verify_dataset(d).ok
    assert _files(d) == _files(ref)  # shards and manifest byte-identical
    # Resumable: a second run finds every shard verified and makes nothing.
    stamps = {p.name: os.stat(p).st_mtime_ns for p in d.glob("*.npz")}
    run_synth(d, CFG, progress=False, ray=RayOptions())
    assert {p.name: os.stat(p).st_mtime_ns for p in d.glob("*.npz")} == stamps


def test_dying_task_is_retried(ray_cluster, ref, tmp_path, monkeypatch):
    """The process making train-00001 exits mid-shard on its first attempt; Ray runs the shard again."""
    marker = tmp_path / "died-once"
    monkeypatch.setenv(FAULT_ENV, f"train-00001.npz@{marker}")
    d = tmp_path / "ds"
    m = run_synth(d, CFG, progress=False, ray=RayOptions(), max_retries=2)
    assert marker.exists()  # the hook fired: a worker died after its first sample
    assert m["complete"] and verify_dataset(d).ok
    assert _files(d) == _files(ref)  # nothing half-written, no temporary file left


def test_shard_that_keeps_failing_is_named(ray_cluster, ref, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(FAULT_ENV, "train-00000.npz")  # every attempt dies
    d = tmp_path / "ds"
    rc = cli.main(["-q", "synth", "--out", str(d), "--res", "32", "--n-dirs", "16", "--shard-size", "2",
                   "--count", "4", "--split-count", "val=1", "--split-count", "test=0",
                   "--ray", ray_cluster.get_runtime_context().gcs_address, "--max-retries", "0"])
    err = capsys.readouterr().err.strip().splitlines()[-1]  # (lines before it: the worker's own log, relayed)
    assert rc == 1
    assert err.startswith(f"relightnet synth: ShardsFailed: {d}: 1 shard(s) failed after 1 attempt(s) "
                          "(train-00000.npz: WorkerCrashedError: "), err
    # The other shards are written and listed; the failed one is not, and nothing else is there.
    assert sorted(p.name for p in d.iterdir()) == ["manifest.json", "train-00001.npz", "val-00000.npz"]
    m = load_manifest(d)
    assert not m["complete"] and [e["index"] for e in m["splits"]["train"]["shards"]] == [1]
    assert (d / "train-00001.npz").read_bytes() == (ref / "train-00001.npz").read_bytes()
    assert verify_dataset(d).problems == (f"{d / 'train-00000.npz'}: not made yet (run 'relightnet synth' "
                                          "again with the same settings)",)


def test_failure_message_names_shards():
    e = ShardsFailed("data/x", [("train-00003.npz", "OSError: disk full")], 3)
    assert str(e) == ("data/x: 1 shard(s) failed after 3 attempt(s) (train-00003.npz: OSError: disk full); "
                      "the other shards are written; run the same command again to retry")
