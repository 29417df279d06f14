import math

import torch

from relightnet.body.base import matrix_to_rotvec, rotvec_to_matrix
from relightnet.fit import default_intrinsics
from relightnet.fit.body_model import FIT_BONES
from relightnet.fit.camera import project_points
from relightnet.fit.smooth import FOOT_SLOTS, gaussian_weights, place_in_world, smooth_motion, smooth_rotations
from relightnet.fit.solve import FitResult


def _result(T=6, seed=0):
    g = torch.Generator().manual_seed(seed)
    pose = 0.1 * torch.randn(T, len(FIT_BONES), 3, generator=g)
    pose[:, 0] = torch.tensor([0.2, 2.9, 0.0])  # turned almost 180°: rotation vectors near the wrap
    trans = torch.tensor([0.1, -0.9, -4.0]) + 0.01 * torch.randn(T, 3, generator=g)
    return FitResult(pose, trans, torch.tensor([0.5, 0.78, 0.5, 0.5, 0.37, 0.5]), default_intrinsics((120, 160)),
                     (120, 160), torch.zeros(T), torch.zeros(T, dtype=torch.bool), 0.0)


def test_weights_rows_sum_to_one():
    w = gaussian_weights(7, 1.5)
    torch.testing.assert_close(w.sum(1), torch.ones(7, dtype=torch.float64))
    assert torch.equal(gaussian_weights(4, 0), torch.eye(4, dtype=torch.float64))


def test_smoothing_keeps_a_constant_rotation_across_the_wrap():
    R = rotvec_to_matrix(torch.tensor([0.0, math.pi - 0.01, 0.0], dtype=torch.float64)).expand(5, 3, 3)
    out = smooth_rotations(R, gaussian_weights(5, 2.0))
    torch.testing.assert_close(out, R, atol=1e-12, rtol=0)


def test_smoothing_lowers_jitter():
    res = _result(T=12)
    sm = smooth_motion(res, 1.5)
    acc = lambda x: (x[2:] - 2 * x[1:-1] + x[:-2]).norm(dim=-1).mean()  # noqa: E731
    assert float(acc(sm.trans)) < 0.5 * float(acc(res.trans))
    assert float(acc(sm.pose[:, 1:])) < 0.5 * float(acc(res.pose[:, 1:]))
    # the root stays near its (constant) orientation: no jump through the rotation-vector wrap
    R0 = rotvec_to_matrix(res.pose[:1, 0].double())
    ang = matrix_to_rotvec(rotvec_to_matrix(sm.pose[:, 0].double()) @ R0.transpose(1, 2)).norm(dim=-1)
    assert float(ang.max()) < 1e-4


def test_world_placement_keeps_the_image_and_grounds_the_feet(fit_body):
    res = _result(T=3)
    with torch.no_grad():
        view_pts, _ = fit_body.points(res.pose, res.trans, fit_body.rest(res.phenotype[None]))
        m = place_in_world(res, fit_body)
        out = fit_body.body(pose=m.pose, trans=m.trans, phenotype=m.phenotype[None])
        w_pts = fit_body.landmarks(out.verts, out.joints)
    V = m.extra["camera_view"].double()
    mapped = fit_body.landmarks.mapped
    back = (w_pts.double() @ V[:3, :3].T + V[:3, 3])[:, mapped]
    torch.testing.assert_close(project_points(back.float(), res.intrinsics),
                               project_points(view_pts[:, mapped], res.intrinsics), atol=0.05, rtol=0)  # pixels
    assert abs(float(w_pts[:, list(FOOT_SLOTS), 1].min())) < 1e-4
    assert m.pose.shape == (3, fit_body.num_joints, 3) and m.bone_names == fit_body.body.joint_names


def test_a_long_fit_is_smoothed_in_blocks_as_by_the_whole_matrix():
    """Beyond SMOOTH_BLOCK frames the band of weights is applied a block of frames at a time (no (T, T) matrix):
    the same smoothing as the whole matrix up to rounding; a clip of at most one block is smoothed bit for bit
    as before (one (T, T) matrix)."""
    from relightnet.fit.smooth import SMOOTH_BLOCK

    T = 2 * SMOOTH_BLOCK + 37
    res = _result(T=T, seed=2)
    sm = smooth_motion(res, 2.0)
    w = gaussian_weights(T, 2.0)
    pose = matrix_to_rotvec(smooth_rotations(rotvec_to_matrix(res.pose.double()), w)).float()
    torch.testing.assert_close(sm.pose, pose, atol=1e-6, rtol=0)
    torch.testing.assert_close(sm.trans, (w @ res.trans.double()).float(), atol=1e-6, rtol=0)
    short = _result(T=SMOOTH_BLOCK, seed=3)
    w = gaussian_weights(SMOOTH_BLOCK, 1.5)
    assert torch.equal(smooth_motion(short, 1.5).trans, (w @ short.trans.double()).to(short.trans.dtype))


def test_a_long_fit_is_placed_in_the_world_a_block_of_frames_at_a_time(fit_body, monkeypatch):
    """place_in_world poses the body's points a block of frames at a time (their lowest foot point and the first
    frame's hips are all it keeps): the same motion as from all frames at once."""
    import relightnet.fit.smooth as smooth

    res = _result(T=7, seed=4)
    whole = place_in_world(res, fit_body)
    monkeypatch.setattr(smooth, "SMOOTH_BLOCK", 3)
    blocks = place_in_world(res, fit_body)
    torch.testing.assert_close(blocks.trans, whole.trans, atol=1e-6, rtol=0)
    assert torch.equal(blocks.pose, whole.pose)
