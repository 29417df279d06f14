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


@pytest.fixture
def masked_clip():
    """``masked_clip(folder, n=3, h=64, w=48)`` → (lossless video, mask folder): a bright block moving
    one pixel per frame over a random background, with its masks."""

    def make(folder, n=3, h=64, w=48):
        import numpy as np

        from relightnet.io import VideoWriter, write_image

        video, masks = folder / "clip.mkv", folder / "masks"
        masks.mkdir()
        g = np.random.default_rng(0)
        with VideoWriter(video, fps=12) as v:
            for t in range(n):
                img = g.integers(40, 90, (h, w, 3), dtype=np.uint8)
                img[8 : h - 8, 14 + t : 30 + t] = 180
                m = np.zeros((h, w, 3), np.uint8)
                m[8 : h - 8, 14 + t : 30 + t] = 255
                v.write(img)
                write_image(masks / f"{t:03d}.png", m)
        return video, masks

    return make
