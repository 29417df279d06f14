"""The capture's preview: the avatar from four sides, framed to its height; the confidence colours."""

import torch

from relightnet.capture import CapturedAvatar, CapturedBody
from relightnet.pipeline.capture_preview import VIEW_ANGLES, _confidence_image, turntable_views


def _avatar(n):
    s = 32
    filled = torch.zeros(s, s, dtype=torch.int8)
    filled[:4], filled[4:8] = 1, 2
    return CapturedAvatar(torch.full((s, s, 3), 0.5), torch.linspace(0, 5, s * s).view(s, s), filled, torch.zeros(n),
                          torch.tensor([0.5, 0.78, 0.5, 0.5, 1.0, 0.5]), 0.8, 3)


def test_four_sides_framed_to_a_tall_person(anny_body):
    views = turntable_views(CapturedBody(anny_body, _avatar(anny_body.num_verts)), 96)
    assert views.shape == (len(VIEW_ANGLES), 96, 72, 3)
    person = views.amax(-1) > 0
    rows = torch.nonzero(person[0].any(1)).squeeze(1)
    assert rows.min() > 0 and rows.max() < 95  # the tallest phenotype is not cut at the top or the bottom
    assert 0.05 < float(person.float().mean()) < 0.5


def test_confidence_colours():
    img = _confidence_image(_avatar(10), 32)
    assert img.shape == (32, 32, 3)
    assert img[1, 1, 0] > img[1, 1, 2] and img[5, 5, 2] > img[5, 5, 0]  # mirrored red, inpainted blue
    assert torch.allclose(img[20, :, 0], img[20, :, 1]) and img[31, 31, 0] > img[10, 0, 0]  # grey rises with weight
