"""The capture's truth clips: a generated person turning in place, its masks, texture and light."""

import numpy as np
import pytest
import torch

from relightnet.capture.truth import light_pair, person_texture, turning_person
from relightnet.checks import InputError, ShapeError
from relightnet.io import read_video, video_info


def test_turning_person_writes_a_turn_and_its_truth(anny_body, tmp_path):
    light, _ = light_pair()
    clip = turning_person(tmp_path, anny_body, light, n_frames=12, size=(128, 128), texture_size=256)
    frames, masks = list(read_video(clip.video)), list(read_video(clip.masks))
    assert len(frames) == len(masks) == 12 and clip.size == (128, 128)
    assert video_info(clip.video).size == video_info(clip.masks).size == (128, 128)
    area = np.array([(m[..., 0] > 127).sum() for m in masks])
    assert (area > 200).all()  # a person in every frame
    assert not (np.stack(masks)[:, [0, -1], :, 0] > 127).any()  # the whole person in frame, head to feet
    assert abs(area[6] - area[0]) < 0.15 * area[0]  # front and back: a turn, not a walk away
    assert area[3] < 0.8 * area[0]  # seen from the side, the A-pose's arms are behind the body
    assert set(np.unique(masks[0])) <= {0, 255}  # the masks are exact
    # the person is the moving part: the background stays where no mask ever was
    outside = ~np.any(np.stack(masks)[..., 0] > 127, 0)
    assert np.abs(frames[5].astype(int) - frames[0].astype(int))[outside].mean() < 2
    assert clip.texture.shape == (256, 256, 3) and clip.texture.dtype == torch.float32
    assert 0.0 < float(clip.texture.min()) and float(clip.texture.max()) <= 1.0
    assert torch.equal(clip.light, light)
    assert clip.params["pose"].shape == (12, anny_body.num_joints, 3) and clip.params["trans"].shape == (12, 3)
    root = clip.params["pose"][:, anny_body.joint_index("root")]
    assert torch.allclose(root[3], torch.tensor([0.0, np.pi / 2, 0.0]), atol=1e-6)  # a quarter turn in 3 frames


def test_person_texture_is_seeded_and_the_lights_differ(anny_body):
    a, b = person_texture(anny_body, 1, 64), person_texture(anny_body, 1, 64)
    assert torch.equal(a, b) and not torch.equal(a, person_texture(anny_body, 2, 64))
    la, lb = light_pair()
    assert la.shape == lb.shape == (9, 3)
    assert float(la[3, 0]) * float(lb[3, 0]) < 0  # keys from opposite sides (the x band)
    assert float(la[3, 0] / la[3, 2]) > 1.5 and float(lb[3, 2] / lb[3, 0]) > 1.5  # a warm key, a cool one


def test_turning_person_refuses_bad_arguments(anny_body, tmp_path):
    light, _ = light_pair()
    with pytest.raises(InputError, match="n_frames"):
        turning_person(tmp_path, anny_body, light, n_frames=1)
    with pytest.raises(InputError, match="size"):
        turning_person(tmp_path, anny_body, light, size=(8, 8))
    with pytest.raises(ShapeError, match="light"):
        turning_person(tmp_path, anny_body, light[:4])
    assert not (tmp_path / "source.mp4").exists()
