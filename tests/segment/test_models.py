"""The shipped ONNX files: their outputs against the source TF Lite models' recorded outputs, the NOTICE."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import numpy as np
import pytest

from relightnet.checks import ShapeError
from relightnet.segment.models import POSE_FILE, SELFIE_FILE, WEIGHTS_DIR

FIXTURE = Path(__file__).with_name("reference_outputs.npz")


def _inputs() -> np.ndarray:
    """The real photos tools/convert_segmentation.py ran the source models on (same slicing)."""
    from skimage import data

    return np.stack([data.astronaut()[::2, ::2], data.chelsea()[22:278, 100:356]]).astype(np.uint8)


@pytest.fixture(scope="module")
def reference():
    ref = dict(np.load(FIXTURE))
    x = _inputs()
    assert hashlib.sha256(x.tobytes()).hexdigest() == str(ref["inputs_sha256"])  # the same pixels
    return x.astype(np.float32) / 255, ref


def test_selfie_model_matches_the_source_model(person_models, reference):
    x, ref = reference
    for i in range(len(x)):
        got = person_models.selfie(x[i])
        want = ref["person_selfie.activation_10"][i, ..., 0].astype(np.float32)
        assert got.shape == (256, 256)
        np.testing.assert_allclose(got, want, atol=2e-3)  # float16 storage + conversion rounding
    # The astronaut is a person, the cat is not.
    assert person_models.selfie(x[0]).mean() > 0.3 and person_models.selfie(x[1]).mean() < 0.05


def test_pose_model_matches_the_source_model(person_models, reference):
    x, ref = reference
    for i in range(len(x)):
        out = person_models.pose(x[i])
        logits = ref["person_pose.Identity_2"][i, ..., 0].astype(np.float32)
        prob = lambda z: 0.5 * (1 + np.tanh(0.5 * z))  # noqa: E731
        np.testing.assert_allclose(prob(out.mask_logits), prob(logits), atol=1e-2)
        assert ((out.mask_logits > 0) != (logits > 0)).mean() < 1e-3
        assert out.presence == pytest.approx(float(ref["person_pose.Identity_1"][i, 0]), abs=1e-4)
        lm = ref["person_pose.Identity"][i].reshape(-1, 5)[:33]
        np.testing.assert_allclose(out.landmarks[:, :3], lm[:, :3], atol=0.05, rtol=1e-2)
        np.testing.assert_allclose(out.world, ref["person_pose.Identity_4"][i].reshape(-1, 3)[:33], atol=1e-3)
        assert out.landmarks.shape == (33, 5) and ((out.landmarks[:, 3:] >= 0) & (out.landmarks[:, 3:] <= 1)).all()
    assert person_models.pose(x[0]).presence > 0.9 and person_models.pose(x[1]).presence < 0.1


def test_bad_input_shape_is_a_shape_error(person_models):
    with pytest.raises(ShapeError, match="selfie input"):
        person_models.selfie(np.zeros((128, 128, 3), np.float32))


def test_notice_names_the_shipped_files_by_checksum_and_they_are_small():
    notice = (WEIGHTS_DIR / "NOTICE").read_text()
    assert "Apache License, Version 2.0" in notice and (WEIGHTS_DIR / "LICENSE-mediapipe.txt").is_file()
    total = 0
    for f in (SELFIE_FILE, POSE_FILE):
        data = f.read_bytes()
        total += len(data)
        row = re.search(rf"\| {f.name}\s+\| ([0-9a-f]{{64}}) \|", notice)
        assert row and row.group(1) == hashlib.sha256(data).hexdigest(), f.name
    assert total <= 15e6  # the budget for the package
