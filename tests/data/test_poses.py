"""relightnet.data.poses: the random phenotypes, poses, motions and yaws of the generated people."""

import json

import numpy as np
import pytest
import torch

from relightnet.body import PHENOTYPES
from relightnet.checks import InputError
from relightnet.data.poses import (
    JOINT_RANGES,
    MOTION_WEIGHTS,
    PRESET_WEIGHTS,
    perturbation,
    sample_phenotype,
    sample_pose,
    sample_yaw,
)
from relightnet.names import MOTION_KINDS, POSE_PRESETS


def test_weights_cover_the_named_poses_and_motions():
    assert set(PRESET_WEIGHTS) <= set(POSE_PRESETS) and set(MOTION_WEIGHTS) == set(MOTION_KINDS)
    assert sum(PRESET_WEIGHTS.values()) == pytest.approx(1) and sum(MOTION_WEIGHTS.values()) == pytest.approx(1)


def test_phenotypes_stay_in_anny_ranges():
    rng = np.random.default_rng(0)
    for _ in range(200):
        p = sample_phenotype(rng, ages=(0.6, 1.0))
        assert set(p) == set(PHENOTYPES)
        assert all(PHENOTYPES[k][0] <= v <= PHENOTYPES[k][1] for k, v in p.items())
        assert 0.6 <= p["age"] <= 1.0


def test_perturbation_is_bounded_by_the_joint_ranges():
    rng = np.random.default_rng(1)
    for magnitude in (0.0, 0.5, 1.0):
        p = perturbation(rng, magnitude)
        assert set(p) == set(JOINT_RANGES)
        for bone, ranges in JOINT_RANGES.items():
            lo = magnitude * np.radians([min(r) for r in ranges]) - 1e-12
            hi = magnitude * np.radians([max(r) for r in ranges]) + 1e-12
            assert np.all(p[bone] >= np.minimum(lo, hi)) and np.all(p[bone] <= np.maximum(lo, hi)), bone


def test_stills_and_clips_are_reproducible_and_described():
    kinds = set()
    for seed in range(30):
        params, desc = sample_pose(np.random.default_rng(seed))
        again, desc2 = sample_pose(np.random.default_rng(seed))
        assert desc == desc2 and json.loads(json.dumps(desc)) == desc
        assert all(torch.equal(params["pose"][b], again["pose"][b]) for b in params["pose"])
        assert params["trans"].shape == (1, 3) and all(v.shape[-1] == 3 for v in params["pose"].values())
        kinds.add(desc["type"])
    assert kinds == {"preset", "motion"}  # both kinds of still occur
    params, desc = sample_pose(np.random.default_rng(3), n_frames=8, kind="walk")
    assert desc["type"] == "motion" and desc["name"] == "walk" and desc["frames"] == 8
    assert params["trans"].shape == (8, 3) and all(v.shape[0] in (1, 8) for v in params["pose"].values())
    with pytest.raises(InputError, match="motion kind: expected one of"):
        sample_pose(np.random.default_rng(0), n_frames=4, kind="dance")


def test_yaw_mostly_frontal():
    rng = np.random.default_rng(2)
    yaws = np.array([sample_yaw(rng) for _ in range(4000)])
    front = np.abs(yaws) <= np.radians(35)
    back = np.abs(yaws - np.pi) <= np.radians(45)
    side = ~front & ~back
    assert np.all(np.abs(yaws[side]) <= np.radians(135) + 1e-9)
    # 60 % frontal, 28 % side, 12 % back by design
    assert abs(front.mean() - 0.6) < 0.04 and abs(side.mean() - 0.28) < 0.04 and abs(back.mean() - 0.12) < 0.03
