import torch

from relightnet.body import POSE_PRESETS
from relightnet.fit.body_model import FIT_BONES
from relightnet.fit.prior import JOINT_LIMITS, limit_bounds, limit_penalty, rest_penalty


def _sub(rotations: dict) -> torch.Tensor:
    sub = torch.zeros(1, len(FIT_BONES), 3)
    for b, v in rotations.items():
        if b in FIT_BONES:
            sub[0, FIT_BONES.index(b)] = torch.tensor(v)
    return sub


def test_presets_are_inside_the_limits():
    lo, hi = limit_bounds()
    for name, rot in POSE_PRESETS.items():
        assert set(rot) <= set(FIT_BONES), name
        assert float(limit_penalty(_sub(rot), lo, hi)[0]) == 0.0, name


def test_penalty_grows_outside_and_rest_pull():
    lo, hi = limit_bounds()
    knee = FIT_BONES.index("lowerleg01.L")
    sub = torch.zeros(2, len(FIT_BONES), 3)
    sub[0, knee, 0] = -0.5  # a knee bent backwards: 0.5 rad − 5° beyond its limit
    sub[1, knee, 0] = 1.0  # an ordinary bend
    p = limit_penalty(sub, lo, hi)
    excess = 0.5 - torch.deg2rad(torch.tensor(5.0))
    torch.testing.assert_close(p[0], excess.square(), atol=1e-6, rtol=1e-5)
    assert float(p[1]) == 0.0
    assert JOINT_LIMITS["root"] is None and float(limit_penalty(_sub({"root": (3.0, 0, 0)}), lo, hi)[0]) == 0.0
    torch.testing.assert_close(rest_penalty(sub), torch.tensor([0.25, 1.0]))
