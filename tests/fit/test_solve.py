"""The fit recovers a known body from evidence made from it (projected landmarks, exact world
landmarks, the rasterized mask)."""

import pytest
import torch

from relightnet.checks import InputError
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


def test_a_window_beyond_the_pixel_budget_is_refused_before_any_work(fit_body):
    """At the 12.5 MP limit 8 frames' distance maps (400 MB) are fitted together, not 9."""
    from relightnet.fit import Observations, default_intrinsics, fit_observations
    from relightnet.fit.masks import PackedMasks
    from relightnet.fit.solve import MAX_WINDOW_PIXELS

    T, size = 9, (3120, 4000)
    masks = PackedMasks(size)
    for _ in range(T):
        masks.append_empty()
    obs = Observations(torch.zeros(T, 33, 5), torch.zeros(T, 33, 3), masks, torch.ones(T, dtype=torch.bool), size)
    assert 8 * 3120 * 4000 <= MAX_WINDOW_PIXELS < 9 * 3120 * 4000
    with pytest.raises(InputError, match=r"a window of 9 frames of 4000x3120 .* at most 8 frames"):
        fit_observations(obs, default_intrinsics(size, 60.0), fit_body, window=9)


def test_fit_restores_the_thread_setting(fit_body):
    obs, intr, _ = known_clip(fit_body, T=1)
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        fit_observations(obs, intr, fit_body, iters=4, warm_iters=2, window=1)
        assert torch.get_num_threads() == 2  # the fit ran on one thread and gave the setting back
    finally:
        torch.set_num_threads(before)


def test_a_fit_that_fails_also_restores_the_thread_setting(fit_body, monkeypatch):
    import relightnet.fit.solve as solve

    def fail(*args):
        assert torch.get_num_threads() == 1
        raise RuntimeError("inside the fit")

    obs, intr, _ = known_clip(fit_body, T=1)
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    monkeypatch.setattr(solve, "_fit_windows", fail)
    try:
        with pytest.raises(RuntimeError, match="inside the fit"):
            fit_observations(obs, intr, fit_body, iters=4, warm_iters=2, window=1)
        assert torch.get_num_threads() == 2
    finally:
        torch.set_num_threads(before)


def test_more_frames_than_the_fit_holds_are_refused_before_any_work(fit_body, tmp_path, monkeypatch):
    """What a fit keeps per frame for the whole video is bounded (fit.MAX_FRAME_BYTES of mask and a few KB), so
    the 2 GiB budget holds MAX_FIT_FRAMES frames; a longer video is refused from its packets' count."""
    import numpy as np

    import relightnet.fit.job as job
    from relightnet.fit import FitOptions, Observations, default_intrinsics, fit_file
    from relightnet.fit.job import MAX_FIT_FRAMES
    from relightnet.io import VideoWriter

    T = MAX_FIT_FRAMES + 1
    obs = Observations(torch.zeros(T, 33, 5), torch.zeros(T, 33, 3), None, torch.ones(T, dtype=torch.bool), (8, 8))
    with pytest.raises(InputError, match=rf"fit: {T} frames; at most {MAX_FIT_FRAMES} frames"):
        fit_observations(obs, default_intrinsics((8, 8), 60.0), fit_body)
    clip = tmp_path / "clip.mp4"
    with VideoWriter(clip, fps=10.0) as w:
        for _ in range(4):
            w.write(np.zeros((32, 32, 3), np.uint8))
    monkeypatch.setattr(job, "MAX_FIT_FRAMES", 3)
    with pytest.raises(InputError, match=r"clip.mp4: 4 frames; at most 3 frames are fitted"):
        fit_file(clip, FitOptions(), fit_body, models=object())  # no model is run: refused first
