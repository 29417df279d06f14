import json
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.data import SynthConfig
from relightnet.data.shards import load_manifest, read_shard, verify_dataset, write_shard
from relightnet.data.synth import make_shard, run_synth

pytestmark = pytest.mark.slow  # generator runs (Anny, PRT) with process pools

CFG = SynthConfig(res=32, n_dirs=16, shard_size=2, counts={"train": 4, "val": 1, "test": 1})


def _files(d):
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


@pytest.fixture(scope="module")
def assets(anny_body):
    """The session's body: the generator keeps its precomputed assets, shared by every in-process run."""
    return anny_body


@pytest.fixture(scope="module")
def ref(tmp_path_factory, assets):
    """A finished tiny dataset made in this process (workers=0)."""
    d = tmp_path_factory.mktemp("ref") / "ds"
    run_synth(d, CFG, workers=0, progress=False, body=assets)
    return d


def test_manifest_and_shards(ref, assets):
    m = load_manifest(ref)
    assert m["complete"] and m["config"] == CFG.to_dict() and m["generator_version"]
    assert [e["file"] for e in m["splits"]["train"]["shards"]] == ["train-00000.npz", "train-00001.npz"]
    assert m["splits"]["val"]["count"] == 1 and m["splits"]["test"]["shards"][0]["count"] == 1
    assert m["fields"]["transport"] == {"shape": [32, 32, 9], "dtype": "float32"}
    assert sorted(p.name for p in ref.iterdir()) == ["manifest.json", "test-00000.npz", "train-00000.npz",
                                                     "train-00001.npz", "val-00000.npz"]
    a = read_shard(ref / "train-00001.npz")
    assert a["image"].shape == (2, 32, 32, 3) and a["light"].shape == (2, 9, 3) and a["parts"].dtype == np.uint8
    assert [x["seed"]["index"] for x in a["meta"]] == [2, 3]
    # The same arrays as making that shard directly.
    b = make_shard(CFG, "train", 1, body=assets)
    assert all(np.array_equal(a[k], b[k]) for k in b if k != "meta")
    assert verify_dataset(ref).ok


def test_resume_repairs_and_recovers(ref, tmp_path, assets):
    d = tmp_path / "ds"
    shutil.copytree(ref, d)
    (d / "train-00000.npz").unlink()  # lost
    data = (d / "val-00000.npz").read_bytes()
    (d / "val-00000.npz").write_bytes(data[:-10] + bytes(10))  # damaged, same size
    m = json.loads((d / "manifest.json").read_text())
    m["splits"]["test"]["shards"] = []  # killed between the shard's rename and the manifest update
    m["complete"] = False
    (d / "manifest.json").write_text(json.dumps(m))
    (d / ".train-00001.npz.abc123.tmp").write_bytes(b"partial")  # a killed writer's temporary file
    kept = os.stat(d / "train-00001.npz").st_mtime_ns
    run_synth(d, CFG, workers=0, progress=False, body=assets)
    assert _files(d) == _files(ref)
    assert os.stat(d / "train-00001.npz").st_mtime_ns == kept  # verified, not remade


def test_killed_run_resumes_to_same_bytes(ref, tmp_path, assets):
    """Kill a 2-worker CLI run after its first shard; finishing in-process gives the same bytes."""
    d = tmp_path / "ds"
    cmd = [sys.executable, "-m", "relightnet.cli", "-q", "synth", "--out", str(d), "--res", "32", "--n-dirs", "16",
           "--shard-size", "2", "--count", "4", "--split-count", "val=1", "--split-count", "test=1",
           "--workers", "2"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if (d / "train-00000.npz").exists():
                break
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    assert (d / "train-00000.npz").exists() and not (d / "test-00000.npz").exists()
    assert (d / "train-00000.npz").read_bytes() == (ref / "train-00000.npz").read_bytes()
    run_synth(d, CFG, workers=0, progress=False, body=assets)
    assert _files(d) == _files(ref)


def test_other_settings_are_refused(ref, tmp_path, assets):
    d = tmp_path / "ds"
    shutil.copytree(ref, d)
    before = {p.name: os.stat(p).st_mtime_ns for p in d.iterdir()}
    with pytest.raises(InputError, match=r"other settings \(res: 32 there, 48 now"):
        run_synth(d, CFG.replace(res=48), workers=0, progress=False)
    with pytest.raises(InputError, match="shrink"):
        run_synth(d, CFG.replace(counts={"train": 2, "val": 1, "test": 1}), workers=0, progress=False)
    assert {p.name: os.stat(p).st_mtime_ns for p in d.iterdir()} == before
    # Counts may grow: the short last shard is remade, the others are kept.
    m = run_synth(d, CFG.replace(counts={"train": 5, "val": 1, "test": 1}), workers=0, progress=False, body=assets)
    assert m["complete"] and [e["count"] for e in m["splits"]["train"]["shards"]] == [2, 2, 1]
    assert (d / "train-00001.npz").read_bytes() == (ref / "train-00001.npz").read_bytes()
    assert verify_dataset(d).ok


def test_verify_catches_problems(ref, tmp_path):
    d = tmp_path / "ds"
    shutil.copytree(ref, d)
    data = bytearray((d / "train-00000.npz").read_bytes())
    data[len(data) // 2] ^= 0xFF
    (d / "train-00000.npz").write_bytes(bytes(data))
    # A wrong shape in a well-formed shard whose checksum the manifest agrees with.
    a = read_shard(d / "val-00000.npz")
    a["meta"] = np.array([json.dumps(x) for x in a["meta"]])
    a["mask"] = a["mask"].reshape(1, 16, 64)
    info = write_shard(d / "val-00000.npz", a)
    m = json.loads((d / "manifest.json").read_text())
    m["splits"]["val"]["shards"][0].update(info)
    (d / "manifest.json").write_text(json.dumps(m))
    (d / "test-00000.npz").unlink()
    shutil.copy(d / "train-00001.npz", d / "train-00009.npz")
    problems = verify_dataset(d).problems
    assert any("train-00000.npz: sha256 mismatch" in p for p in problems)
    assert any("val-00000.npz: mask is float32[1, 16, 64], expected float32[1, 32, 32]" in p for p in problems)
    assert any("test-00000.npz: missing" in p for p in problems)
    assert any("train-00009.npz: shard file not in the manifest" in p for p in problems)
    assert len(problems) == 4, problems  # one line per problem
    assert "dataset folder not found" in verify_dataset(tmp_path / "nope").problems[0]


def test_sequences(tmp_path, assets):
    cfg = SynthConfig(res=32, n_dirs=16, shard_size=1, counts={"train": 1, "val": 0, "test": 0}, sequence_frames=2)
    m = run_synth(tmp_path / "clips", cfg, workers=0, progress=False, body=assets)
    assert m["fields"]["image"]["shape"] == [2, 32, 32, 3] and m["fields"]["light"]["shape"] == [2, 9, 3]
    a = read_shard(tmp_path / "clips" / "train-00000.npz")
    assert a["transport"].shape == (1, 2, 32, 32, 9) and a["meta"][0]["n_frames"] == 2
    assert verify_dataset(tmp_path / "clips").ok
