import torch

from relightnet.fit.landmarks import LANDMARK_SOURCES, landmark_weights
from relightnet.segment import LANDMARK_NAMES


def test_every_blazepose_landmark_has_an_entry():
    assert list(LANDMARK_SOURCES) == list(LANDMARK_NAMES)
    mapped = [n for n, s in LANDMARK_SOURCES.items() if s is not None]
    assert len(mapped) == 27  # 21 points of the COCO regressor (toes as foot_index) + 6 hand joints


def test_points_match_anny_regressor_and_sides(fit_body, anny_body):
    import anny

    out = anny_body(pose=anny_body.pose("tpose"))
    pts = fit_body.landmarks(out.verts, out.joints)[0]
    reg = anny.KeypointsRegressor.coco(anny_body.anny)
    ref = reg({"vertices": out.verts})[0]
    for i, name in enumerate(LANDMARK_NAMES):
        src = LANDMARK_SOURCES[name]
        if src is None:
            assert torch.equal(pts[i], torch.zeros(3))
            continue
        if src[0] == "coco":
            torch.testing.assert_close(pts[i], ref[list(reg.labels).index(src[1])], atol=1e-5, rtol=0)
        # the person's left is +x (faces +z), as BlazePose's left is the person's own
        if name.startswith("left_"):
            assert pts[i, 0] > 0.02, name
        if name.startswith("right_"):
            assert pts[i, 0] < -0.02, name


def test_anatomy_order_and_hands(fit_body, anny_body):
    out = anny_body(pose=anny_body.pose("tpose"))
    p = dict(zip(LANDMARK_NAMES, fit_body.landmarks(out.verts, out.joints)[0], strict=True))
    y = {k: float(v[1]) for k, v in p.items()}
    assert y["nose"] > y["left_shoulder"] > y["left_hip"] > y["left_knee"] > y["left_ankle"] > y["left_heel"]
    # T-pose: the hand points lie beyond the wrist, along the arm (x grows outward)
    for side, sgn in (("left", 1), ("right", -1)):
        w = float(p[f"{side}_wrist"][0]) * sgn
        for h in ("pinky", "index"):
            assert float(p[f"{side}_{h}"][0]) * sgn > w + 0.03
        # the toe is in front of the heel
        assert float(p[f"{side}_foot_index"][2]) > float(p[f"{side}_heel"][2]) + 0.1


def test_weights_zero_unmapped_and_low_visibility(fit_body):
    vis = torch.full((2, 33), 0.9)
    vis[0, 0] = 0.01
    w = landmark_weights(vis, fit_body.landmarks.mapped)
    assert float(w[0, 0]) == 0.0 and abs(float(w[1, 0]) - 0.9) < 1e-6
    unmapped = ~fit_body.landmarks.mapped
    assert bool((w[:, unmapped] == 0).all())
