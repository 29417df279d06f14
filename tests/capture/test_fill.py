"""Unseen texels: the mirror image first, then the mesh around them within the body part."""

import numpy as np
import torch

from relightnet.capture.fill import fill_unseen, mirror_texels


def test_mirror_texels_pair_left_and_right():
    pts = np.array([[-0.2, 1.0, 0.0], [0.2, 1.0, 0.0], [0.0, 1.5, 0.1], [0.5, 0.2, 0.0]], np.float32)
    m = mirror_texels(pts)
    assert m[0] == 1 and m[1] == 0 and m[2] == 2 and m[3] == -1  # the last has no mirror image within 1 cm


def test_fill_takes_the_mirror_then_diffuses_within_the_part():
    # A strip of 6 vertices (two parts: 0-2 and 3-5), one texel per vertex at barycentrics (1, 0, 0).
    faces = torch.tensor([[0, 1, 2], [1, 2, 3], [2, 3, 4], [3, 4, 5]])
    parts = torch.tensor([0, 0, 0, 1, 1, 1])
    tri = torch.stack([torch.arange(6), (torch.arange(6) + 1) % 6, (torch.arange(6) + 2) % 6], 1)
    bary = torch.tensor([[1.0, 0.0, 0.0]]).expand(6, 3)
    values = torch.tensor([[1.0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 1.0], [0, 0, 0], [0, 0, 0]])
    seen = torch.tensor([True, False, False, True, False, False])
    mirror = torch.tensor([-1, -1, -1, -1, -1, 3])  # texel 5 mirrors texel 3
    out, how = fill_unseen(values, seen, tri, bary, mirror, faces, parts, 6)
    assert how.tolist() == [0, 2, 2, 0, 2, 1]
    assert torch.allclose(out[5], values[3])
    assert torch.allclose(out[1], torch.tensor([1.0, 0, 0])) and torch.allclose(out[2], torch.tensor([1.0, 0, 0]))
    assert torch.allclose(out[4], torch.tensor([0, 0, 1.0]))  # from its own part, though vertex 2 is nearer too
