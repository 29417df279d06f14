"""Pipeline-test fixtures: running a command in a child process and killing it mid-run; generated test clips
(``seq_dir``, ``clip0``) and the shipped model."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import torch

#: frames and side of the generated test clips
T = 3
RES = 32


def temp_files(folder: Path) -> list[Path]:
    """Hidden temporary files and staging folders (``.name.….tmp``) left in ``folder``."""
    return sorted(p for p in folder.iterdir() if p.name.startswith(".") and p.name.endswith(".tmp"))


@pytest.fixture
def kill_mid_run():
    """``kill_mid_run(argv, folder, ready)`` runs ``relightnet ARGV`` in a child process, SIGKILLs it
    as soon as ``ready(temp_files(folder))`` is true (it is writing), and returns the temporary
    files it left. Fails if the command ends before that."""

    def run(argv, folder: Path, ready=lambda temps: any(p.is_file() and p.stat().st_size for p in temps),
            timeout: float = 900.0) -> list[Path]:
        env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
        child = subprocess.Popen([sys.executable, "-m", "relightnet.cli", "-q", *argv], env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        end = time.monotonic() + timeout
        try:
            while child.poll() is None and time.monotonic() < end:
                if ready(temp_files(folder)):
                    child.send_signal(signal.SIGKILL)
                    child.wait()
                    return temp_files(folder)
                time.sleep(0.005)
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()
        pytest.fail(f"relightnet {argv[0]} ended (rc {child.returncode}) before it could be killed mid-run: "
                    f"{child.stderr.read().decode()[-500:]}")

    return run


@pytest.fixture(scope="session")
def seq_dir(tmp_path_factory, anny_body):
    """2 test clips of 3 frames at 32², one clip per shard."""
    from relightnet.data import SynthConfig, run_synth

    out = tmp_path_factory.mktemp("seq") / "clips"
    cfg = SynthConfig(seed=4, res=RES, n_dirs=16, shard_size=1, counts={"train": 0, "val": 0, "test": 2},
                      sequence_frames=T)
    run_synth(out, cfg, workers=0, progress=False, body=anny_body)
    return out


@pytest.fixture(scope="session")
def clip0(seq_dir, anny_body):
    """(config, meta, arrays of CLIP_FIELDS, ClipGeometry) of test clip 0."""
    from relightnet.data import load_manifest, read_shard
    from relightnet.data.render_sample import clip_geometry
    from relightnet.data.shards import dataset_config
    from relightnet.pipeline.compare import CLIP_FIELDS

    cfg = dataset_config(load_manifest(seq_dir))
    a = read_shard(seq_dir / "test-00000.npz")
    n = torch.get_num_threads()
    torch.set_num_threads(1)  # as the generator ran
    try:
        geo = clip_geometry(cfg, "test", 0, T, anny_body)
    finally:
        torch.set_num_threads(n)
    return cfg, a["meta"][0], {k: a[k][0] for k in CLIP_FIELDS}, geo


@pytest.fixture(scope="session")
def model():
    """The shipped model."""
    from relightnet.model import load_model

    return load_model()
