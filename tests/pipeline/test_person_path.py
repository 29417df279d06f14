"""The avatar's path that follows the target's person: a robust track of the masks' boxes, and its placement."""

import math

import numpy as np
import torch

from relightnet.pipeline.clean_plate import Placement, placed_camera
from relightnet.pipeline.person_path import path_offsets, smooth_track


def test_smooth_track_follows_a_line_through_gaps_cuts_and_an_outlier():
    T = 40
    t = np.arange(T, dtype=np.float64)
    truth = np.stack([20 + 3 * t, 100 + 0.5 * t, 80 + 0.2 * t], 1)
    rng = np.random.default_rng(0)
    boxes = [tuple(b) for b in truth + rng.normal(0, 0.5, truth.shape)]
    for k in (0, 1, 2, 3):  # entering: cut by the frame's edge
        boxes[k] = (math.nan, math.nan, math.nan)
    boxes[10] = None  # no person found
    boxes[20] = (300.0, 60.0, 30.0)  # a stray blob
    boxes[30] = (truth[30, 0] + 25, truth[30, 1], truth[30, 2])  # one frame's mask lost a leg: a jump in u
    out = smooth_track(boxes, (0.0, 0.0, 1.0))
    err = np.abs(out - truth)
    # The noise is 0.5 px: the median and the spline leave a fraction of it along the line; the single jump
    # of 25 px is voted out by the median, which it moves by at most one rank (half of the 3 px a frame
    # moves, plus noise); the stray blob (a fifth of the height away) is dropped.
    assert np.median(err[4:]) < 0.5 and err[4:].max() < 1.5 + 3 * 0.5, err[4:].max(0)
    # Before its first value the track goes on at its speed (u, v) and holds the height.
    assert np.abs(err[:4, :2]).max() < 1.5 and np.abs(out[:4, 2] - out[4, 2]).max() < 1e-9
    flat = smooth_track([None, (5.0, math.nan, 7.0), None], (1.0, 2.0, 3.0))
    assert np.allclose(flat, [[5.0, 2.0, 7.0]] * 3)


def test_path_offsets_put_the_feet_and_the_height_where_the_track_says():
    size, H_body = (180, 240), 1.7
    where = Placement((130.0, 160.0), 120.0)
    cam = placed_camera(size, where, H_body)
    track = np.array([[130.0, 160.0, 120.0], [60.0, 150.0, 100.0], [200.0, 170.0, 140.0]])
    off = path_offsets(size, where, track, H_body)
    assert torch.allclose(off[0], torch.zeros(3), atol=1e-5)  # the median frame: the origin
    for k in range(3):
        feet, head = off[k].clone(), off[k].clone()
        head[1] += H_body
        clip = cam.transform(torch.stack([feet, head]))[0]
        ndc = clip[:, :2] / clip[:, 3:]
        px = torch.stack([(ndc[:, 0] + 1) * size[1] / 2, (1 - ndc[:, 1]) * size[0] / 2], 1)
        assert torch.allclose(px[0], torch.tensor(track[k, :2], dtype=torch.float32), atol=1e-2)
        assert abs(float(px[0, 1] - px[1, 1]) - track[k, 2]) < 1e-2
