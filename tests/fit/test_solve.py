"""The fit recovers a known body from evidence made from it (projected landmarks, exact world
landmarks, the rasterized mask)."""

import torch

from relightnet.fit import fit_observations
from relightnet.fit.metrics import mpjpe
from tests.fit.conftest import known_clip


def test_fit_recovers_a_known_pose(fit_body):
    obs, intr, truth = known_clip(fit_body, T=2)
    res = fit_observations(obs, intr, fit_body, iters=60, warm_iters=20, window=2)
    with torch.no_grad():
        pts, _ = fit_body.points(res.pose, res.trans, fit_body.rest(res.phenotype[None]))
        rest_pts, _ = fit_body.points(torch.zeros_like(res.pose), res.trans, fit_body.rest(res.phenotype[None]))
    mapped = fit_body.landmarks.mapped
    err = mpjpe(pts, truth, mapped)
    err_rest = mpjpe(rest_pts, truth, mapped)
    # exact evidence: the fit lands within a few cm of the truth and far below the rest pose
    assert bool((err < 45).all()), err
    assert bool((err < 0.5 * err_rest).all()), (err, err_rest)
    assert bool((res.residual_2d < 0.03).all()), res.residual_2d
    assert res.pose.shape == (2, len(fit_body.bone_index), 3) and not bool(res.interpolated.any())


def test_fit_restores_the_thread_setting(fit_body):
    obs, intr, _ = known_clip(fit_body, T=1)
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        fit_observations(obs, intr, fit_body, iters=4, warm_iters=2, window=1)
        assert torch.get_num_threads() == 2  # the fit ran on one thread and gave the setting back
    finally:
        torch.set_num_threads(before)
