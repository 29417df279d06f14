import math

import torch

from relightnet.fit.metrics import acceleration_error, foot_skating, landmark_error, mask_iou, mpjpe, pa_mpjpe


def _pts(T=4, seed=0):
    return torch.randn(T, 33, 3, generator=torch.Generator().manual_seed(seed))


def test_errors_of_the_truth_are_zero_and_procrustes_removes_similarity():
    x = _pts()
    mapped = torch.ones(33, dtype=torch.bool)
    assert float(mpjpe(x, x, mapped).max()) == 0.0
    c, s = math.cos(0.7), math.sin(0.7)
    R = torch.tensor([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    y = 1.3 * x @ R.T + torch.tensor([0.5, -0.2, 3.0])
    assert float(pa_mpjpe(y, x, mapped).max()) < 1e-3  # mm
    assert float(mpjpe(y, x, mapped).min()) > 100.0
    assert float(acceleration_error(x, x, mapped).max()) == 0.0


def test_known_values():
    x = torch.zeros(3, 33, 3)
    mapped = torch.zeros(33, dtype=torch.bool)
    mapped[[0, 23, 24]] = True
    y = x.clone()
    y[:, 0, 0] = 0.01  # one of three points off by 1 cm
    torch.testing.assert_close(mpjpe(y, x, mapped), torch.full((3,), 10.0 / 3))
    y[1, 0, 1] = 0.002  # a 2 mm bump in the middle frame: second difference -4 mm, on 1 of 3 points
    torch.testing.assert_close(acceleration_error(y, x, mapped), torch.tensor([4.0 / 3]))


def test_foot_skating_and_iou():
    T = 5
    p = torch.zeros(T, 33, 3)
    p[:, 29, 0] = torch.arange(T) * 0.004  # a heel on the ground sliding 4 mm per frame
    p[:, 30, 1] = 0.2  # the other foot in the air
    p[:, 31, 1] = 0.2
    p[:, 32, 1] = 0.2
    assert abs(foot_skating(p) - 4.0) < 1e-6
    p[:, 29, 0] = 0.0
    assert foot_skating(p) == 0.0
    a = torch.zeros(1, 4, 4)
    a[0, :2] = 1
    b = torch.zeros(1, 4, 4)
    b[0, 1:3] = 1
    torch.testing.assert_close(mask_iou(a, b), torch.tensor([1 / 3], dtype=torch.float64))
    px = torch.zeros(1, 33, 2)
    e = landmark_error(px + 3.0 / math.sqrt(2), px, torch.ones(33, dtype=torch.bool), torch.tensor([300.0]))
    assert abs(float(e[0]) - 1.0) < 1e-5
