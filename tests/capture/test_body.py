"""The captured person as a body: the captured shape, the offsets along the posed normals."""

import torch

from relightnet.capture import CapturedAvatar, CapturedBody
from relightnet.checks import InputError


def _avatar(n, offsets):
    s = 16
    return CapturedAvatar(torch.full((s, s, 3), 0.5), torch.ones(s, s), torch.zeros(s, s, dtype=torch.int8),
                          offsets, torch.tensor([0.5, 0.78, 0.5, 0.9, 0.37, 0.5]), 1.0, 2)


def test_offsets_pose_with_the_body_and_the_shape_is_the_captured_one(anny_body):
    V = anny_body.num_verts
    d = torch.zeros(V)
    d[: V // 2] = 0.03
    cb = CapturedBody(anny_body, _avatar(V, d))
    pose = torch.zeros(2, anny_body.num_joints, 3)
    pose[1, 0, 1] = 1.2  # turned: the offsets turn with the normals
    out = cb({"pose": pose, "trans": torch.zeros(2, 3), "phenotype": torch.full((1, 6), 0.5)})
    bare = anny_body({"pose": pose, "trans": torch.zeros(2, 3), "phenotype": cb.avatar.phenotype[None]})
    step = out.verts - bare.verts
    assert torch.allclose(step[:, : V // 2].norm(dim=-1), torch.full((2, V // 2), 0.03), atol=1e-5)
    assert torch.allclose(step, d[None, :, None] * bare.normals, atol=1e-6)
    assert step[:, V // 2:].abs().max() < 1e-6
    assert torch.allclose(out.normals.norm(dim=-1), torch.ones(2, V), atol=1e-4)
    assert cb.albedo.tex.shape == (16, 16, 3)


def test_another_body_is_refused(anny_body):
    try:
        CapturedBody(anny_body, _avatar(10, torch.zeros(10)))
    except InputError as e:
        assert "10 vertices" in str(e)
    else:
        raise AssertionError("expected an InputError")
