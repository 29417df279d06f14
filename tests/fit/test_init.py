"""The initial orientation of a warm-started window follows the torso's turn in the world landmarks."""

import math

import torch

from relightnet.body.base import matrix_to_rotvec, rotvec_to_matrix
from relightnet.fit.init import MAX_TURN_DEG, relative_turn


def _torso(T: int, yaws_deg) -> torch.Tensor:
    """(T, 33, 3) world landmarks: a fixed random point set turned about y by each frame's yaw."""
    g = torch.Generator().manual_seed(3)
    base = torch.randn(33, 3, generator=g, dtype=torch.float64) * 0.3
    R = rotvec_to_matrix(torch.tensor([[0.0, math.radians(a), 0.0] for a in yaws_deg], dtype=torch.float64))
    return (R[:, None] @ base[None, :, :, None])[..., 0]


def test_turns_chain_over_frames_beyond_one_step_limit():
    yaws = [0, 40, 80, 120, 160, 200]  # 200° in all: more than any one step may turn
    w = torch.ones(6, 33, dtype=torch.float64)
    R = relative_turn(_torso(6, yaws), w)
    got = torch.rad2deg(matrix_to_rotvec(R))
    want = torch.tensor([[0.0, a, 0.0] for a in (40, 80, 120, 160, -160)], dtype=torch.float64)
    # exact landmarks: Kabsch recovers each step to float64 rounding of 0.3 m points
    torch.testing.assert_close(got, want, atol=1e-6, rtol=0)


def test_a_swap_sized_step_or_an_unseen_torso_is_no_turn():
    yaws = [0, 30, 30 + MAX_TURN_DEG + 30, 30 + MAX_TURN_DEG + 60]
    w = torch.ones(4, 33, dtype=torch.float64)
    R = relative_turn(_torso(4, yaws), w)
    got = torch.rad2deg(matrix_to_rotvec(R))[:, 1]
    torch.testing.assert_close(got, torch.tensor([30.0, 30.0, 60.0], dtype=torch.float64), atol=1e-6, rtol=0)
    w[1, 11] = 0  # a shoulder unseen in frame 1: steps 0→1 and 1→2 are not followed
    got = torch.rad2deg(matrix_to_rotvec(relative_turn(_torso(4, [0, 30, 60, 90]), w)))[:, 1]
    torch.testing.assert_close(got, torch.tensor([0.0, 0.0, 30.0], dtype=torch.float64), atol=1e-6, rtol=0)
