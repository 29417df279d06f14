import torch

from relightnet.body import AnnyMotion, make_motion
from relightnet.fit.metrics import foot_skating
from relightnet.fit.retarget import leg_length, retarget_motion
from relightnet.fit.smooth import FOOT_SLOTS


def _walk(fb, T=16):
    m = make_motion("walk", T, fps=30, seed=3)
    pose = fb.body.pose_from_dict(m["pose"], T)
    trans = m["trans"].clone()
    trans[:, 2] += torch.linspace(0, 0.4, T)  # a root sliding forward faster than the steps: skating feet
    return AnnyMotion(pose, trans, torch.tensor([0.5, 0.78, 0.5, 0.5, 0.37, 0.5]), fb.body.joint_names)


def _landmarks(fb, m):
    with torch.no_grad():
        out = fb.body(pose=m.pose, trans=m.trans, phenotype=m.phenotype[None])
        return fb.landmarks(out.verts, out.joints)


def test_feet_stay_put_and_on_the_ground(fit_body):
    m = _walk(fit_body)
    before = foot_skating(_landmarks(fit_body, m))
    moved = retarget_motion(m, fit_body)
    pts = _landmarks(fit_body, moved)
    after = foot_skating(pts)
    assert after < 0.5 * before and after < 5.0, (before, after)
    assert abs(float(pts[:, list(FOOT_SLOTS), 1].min())) < 1e-4


def test_path_scales_with_leg_length(fit_body):
    m = _walk(fit_body)
    tall = torch.tensor([0.5, 0.78, 0.5, 0.5, 0.8, 0.5])
    ratio = leg_length(fit_body, tall) / leg_length(fit_body, m.phenotype)
    assert ratio > 1.1
    moved = retarget_motion(m, fit_body, tall, lock_feet=False)
    d0 = (m.trans[-1, [0, 2]] - m.trans[0, [0, 2]]).norm()
    d1 = (moved.trans[-1, [0, 2]] - moved.trans[0, [0, 2]]).norm()
    torch.testing.assert_close(d1 / d0, torch.tensor(ratio), atol=1e-4, rtol=0)
    assert torch.equal(moved.pose, m.pose) and torch.equal(moved.phenotype, tall)
