import math

import pytest
import torch

from relightnet.body import MOTION_KINDS, make_motion
from relightnet.checks import InputError


def _joint(out, name):
    return out.joints[:, out.joint_names.index(name)]


def test_all_kinds_run_through_anny(anny_body):
    for kind in MOTION_KINDS:
        m = make_motion(kind, 8, seed=3)
        assert set(m) == {"pose", "trans"} and m["trans"].shape == (8, 3)
        assert all(r.shape == (8, 3) and r.dtype == torch.float32 for r in m["pose"].values())
        assert set(m["pose"]) <= set(anny_body.joint_names)
        out = anny_body(m)
        assert out.verts.shape == (8, anny_body.num_verts, 3) and torch.isfinite(out.verts).all()


def test_seeded_determinism():
    a, b, c = make_motion("walk", 20, seed=7), make_motion("walk", 20, seed=7), make_motion("walk", 20, seed=8)
    assert all(torch.equal(a["pose"][k], b["pose"][k]) for k in a["pose"]) and torch.equal(a["trans"], b["trans"])
    assert any(not torch.allclose(a["pose"][k], c["pose"][k]) for k in a["pose"])


def test_walk_is_periodic_and_advances():
    m = make_motion("walk", 61, fps=30, seed=1, freq=1.0)
    for k, r in m["pose"].items():
        assert torch.allclose(r[:31], r[30:], atol=1e-5), k
    assert torch.allclose(m["trans"][:31], m["trans"][30:], atol=1e-6)
    fwd = make_motion("walk", 61, fps=30, seed=1, freq=1.0, advance=True, stride_length=1.3)
    dz = fwd["trans"][:, 2].diff()
    assert (dz > 0).all() and abs(fwd["trans"][30, 2] - fwd["trans"][0, 2] - 1.3) < 1e-5


@pytest.mark.slow
def test_walk_is_smooth_and_plausible(anny_body):
    out = anny_body(make_motion("walk", 40, fps=30, seed=2))
    j = out.joints
    assert j.diff(dim=0).norm(dim=-1).max() < 0.15  # < 4.5 m/s for any joint (the swinging toes are fastest)
    acc30 = j.diff(n=2, dim=0).norm(dim=-1).max()
    assert acc30 < 0.04  # < 36 m/s², the swinging toes being the fastest
    # C1: for a smooth motion the second difference shrinks as 1/fps²; a kink would shrink as 1/fps.
    j60 = anny_body(make_motion("walk", 80, fps=60, seed=2)).joints
    assert j60.diff(n=2, dim=0).norm(dim=-1).max() < 0.3 * acc30
    la, ra = _joint(out, "foot.L"), _joint(out, "foot.R")
    assert la[:, 2].max() - la[:, 2].min() > 0.3  # the legs swing
    assert (la[:, 2] - ra[:, 2]).abs().max() > 0.3  # in opposition
    lw = _joint(out, "wrist.L")[:, 2]
    corr = torch.corrcoef(torch.stack([lw, la[:, 2]]))[0, 1]
    assert corr < -0.5  # arms counter-swing
    knee = _joint(out, "lowerleg01.L")
    thigh, shin = knee - _joint(out, "upperleg01.L"), la - knee
    bend = torch.acos((thigh * shin).sum(-1) / thigh.norm(dim=-1) / shin.norm(dim=-1))
    assert bend.max() > math.radians(40) and bend.min() < math.radians(15)  # knees bend in swing
    pelvis_y = _joint(out, "root")[:, 1]
    assert 0.01 < pelvis_y.max() - pelvis_y.min() < 0.08  # small vertical bob


def test_turn_in_place(anny_body):
    m = make_motion("turn", 31, fps=30, seed=0, angle=math.pi / 2)
    out = anny_body(m)
    face = (_joint(out, "eye.L") + _joint(out, "eye.R")) / 2 - _joint(out, "head")
    assert face[0, 2] > 0.05 and abs(face[0, 0]) < 0.03  # starts facing +z
    assert face[-1, 0] > 0.05 and abs(face[-1, 2]) < 0.03  # ends facing +x
    pelvis = _joint(out, "root")
    assert (pelvis[:, [0, 2]] - pelvis[0, [0, 2]]).norm(dim=-1).max() < 0.05  # in place
    yaw = m["pose"]["root"][:, 1]
    assert abs(yaw[1] - yaw[0]) < 0.01 and abs(yaw[-1] - yaw[-2]) < 0.01  # eased in and out
    assert out.joints.diff(n=2, dim=0).norm(dim=-1).max() < 0.02


def test_idle_moves_a_little(anny_body):
    out = anny_body(make_motion("idle", 60, fps=30, seed=4))
    span = (out.joints - out.joints.mean(0)).norm(dim=-1).amax(0)
    assert 0.002 < span.max() < 0.1
    assert out.joints.diff(n=2, dim=0).norm(dim=-1).max() < 0.005


def test_arm_raise(anny_body):
    m = make_motion("arm_raise", 61, fps=20, seed=0, side="left", height=math.radians(140), period=3.0)
    out = anny_body(m)
    lw, rw, head = _joint(out, "wrist.L"), _joint(out, "wrist.R"), _joint(out, "head")
    assert lw[30, 1] > head[30, 1] and lw[0, 1] < head[0, 1] - 0.4 and lw[-1, 1] < head[-1, 1] - 0.4
    assert (rw[:, 1] - rw[0, 1]).abs().max() < 0.05
    assert out.joints.diff(n=2, dim=0).norm(dim=-1).max() < 0.03


def test_errors():
    with pytest.raises(InputError, match="motion kind"):
        make_motion("dance", 10)
    with pytest.raises(InputError, match="unknown option.*'speeed'"):
        make_motion("walk", 10, speeed=2)
    with pytest.raises(InputError, match="n_frames"):
        make_motion("walk", 0)
    with pytest.raises(InputError, match="side"):
        make_motion("arm_raise", 10, side="up")
