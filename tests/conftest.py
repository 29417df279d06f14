"""Fixtures shared by every test folder: the Anny cache location and one Anny model per session."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# `make test` exports ANNY_CACHE_DIR; a bare `pytest` run uses the same repo cache.
os.environ.setdefault("ANNY_CACHE_DIR", str(Path(__file__).resolve().parents[1] / ".cache" / "anny"))
os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(scope="session")
def anny_body():
    """The default AnnyBody (float32, feet on y = 0), built once per test session."""
    from relightnet.body import AnnyBody

    return AnnyBody()


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory, anny_body):
    """A real dataset folder made by the generator: 6 train and 3 test samples at 32², 16 PRT directions."""
    from relightnet.data import SynthConfig
    from relightnet.data.synth import run_synth

    out = tmp_path_factory.mktemp("data") / "tiny"
    cfg = SynthConfig(seed=3, res=32, n_dirs=16, shard_size=4, counts={"train": 6, "test": 3})
    run_synth(out, cfg, workers=0, progress=False, body=anny_body)
    return out
