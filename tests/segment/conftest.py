"""Segmentation fixtures: the loaded models, real photos, generated people over real backgrounds."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import torch

sys.path.insert(0, str(Path(__file__).parent))
from people import background, person_cutout, place  # noqa: E402


@pytest.fixture(scope="session")
def person_models():
    from relightnet.segment import PersonModels

    return PersonModels(threads=2)


@pytest.fixture(scope="session")
def astronaut() -> torch.Tensor:
    """scikit-image's astronaut photo (a real photo of a person): (3, 512, 512) sRGB in [0, 1]."""
    from skimage import data

    return torch.from_numpy(data.astronaut()).permute(2, 0, 1).float() / 255


@pytest.fixture(scope="session")
def generated_people(anny_body):
    """Two people made by the package's generator (256², test split): (person (3, h, w), coverage (h, w)) each."""
    from relightnet.data import SynthConfig
    from relightnet.data.generate import generate_sample

    cfg = SynthConfig(res=256, n_dirs=16, prt_reuse=1)  # two people, not one seen twice
    return [person_cutout(generate_sample(cfg, "test", i, body=anny_body).arrays) for i in (0, 1)]


@pytest.fixture(scope="session")
def person_scene(generated_people):
    """A generated person over a real photograph (coffee), 360 x 640: (image (3, H, W), true mask (H, W))."""
    person, cover = generated_people[0]
    return place(background("coffee", (360, 640)), person, cover, height=0.8, cx=0.4, bottom=0.93)


@pytest.fixture(scope="session")
def walking_clip(anny_body):
    """6 frames of a generated person walking (moving right 6 px a frame) over a real photograph (rocket),
    240 x 320: (frames [(3, H, W)], true masks [(H, W)])."""
    from relightnet.data import SynthConfig
    from relightnet.data.generate import generate_sequence

    a = generate_sequence(SynthConfig(res=192, n_dirs=16), "test", 1, 6, body=anny_body).arrays
    ys, xs = np.nonzero(a["mask"].max(0) > 0.5)
    box = (slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1))
    bg = background("rocket", (240, 320))
    frames, masks = [], []
    for t in range(6):
        person, cover = person_cutout({"image": a["image"][t], "mask": a["mask"][t]}, crop=box)
        img, m = place(bg, person, cover, height=0.85, cx=0.4 + 6 * t / 320, bottom=0.95)
        frames.append(img)
        masks.append(m)
    return frames, masks
