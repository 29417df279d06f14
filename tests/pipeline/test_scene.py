import json

import numpy as np
import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.io import write_image
from relightnet.pipeline.scene import avatar_albedo, load_body, load_camera, motion_params, open_motion
from relightnet.render import TexturedAlbedo


def test_load_body(anny_body):
    assert load_body(anny_body) is anny_body
    with pytest.raises(InputError, match="'anny' or 'smpl:PATH'"):
        load_body("mannequin")


def test_motion_params(anny_body, tmp_path):
    params, n = motion_params("walk", anny_body, 7, fps=24)
    assert n == 7 and all(v.shape == (7, 3) for v in params["pose"].values())
    given = {"pose": {"root": torch.zeros(5, 3)}, "trans": torch.zeros(5, 3), "phenotype": {"age": 0.5}}
    assert motion_params(given, anny_body, 99)[1] == 5
    with pytest.raises(ShapeError, match="disagree"):
        motion_params({"pose": {"root": torch.zeros(5, 3)}, "trans": torch.zeros(4, 3)}, anny_body, 5)
    with pytest.raises(InputError, match="moonwalk"):
        motion_params("moonwalk", anny_body, 5)
    np.savez(tmp_path / "m.npz", poses=np.zeros((3, 72), np.float32))
    with pytest.raises(InputError, match="SMPL body"):
        motion_params(str(tmp_path / "m.npz"), anny_body, 5)


def test_open_motion_checks_now_and_makes_frames_later(anny_body):
    with pytest.raises(InputError, match="moonwalk"):
        open_motion("moonwalk", anny_body)  # before any frame is asked for
    frames = open_motion("arm_raise", anny_body, fps=24)
    for n in (3, 11):  # a preset is made as long as asked, the same as motion_params
        params, t = frames(n)
        ref, _ = motion_params("arm_raise", anny_body, n, fps=24)
        assert t == n and all(torch.equal(params["pose"][k], ref["pose"][k]) for k in ref["pose"])
    given = {"pose": {"root": torch.zeros(5, 3)}, "trans": torch.zeros(5, 3)}
    assert open_motion(given, anny_body)(99)[1] == 5  # a mapping keeps its own length


def test_avatar_albedo(anny_body, tmp_path):
    default = avatar_albedo(anny_body)
    assert isinstance(default, TexturedAlbedo) and avatar_albedo(anny_body, default) is default
    v = torch.full((anny_body.num_verts, 3), 0.5)
    assert torch.equal(avatar_albedo(anny_body, v), v)
    with pytest.raises(ShapeError, match="albedo"):
        avatar_albedo(anny_body, torch.ones(10, 3))
    tex = np.full((16, 16, 3), 188, np.uint8)
    write_image(tmp_path / "t.png", tex, srgb=False)
    t = avatar_albedo(anny_body, str(tmp_path / "t.png"))
    assert t.tex.shape == (16, 16, 3) and abs(float(t.tex.mean()) - 0.5) < 0.01  # sRGB 188 → linear 0.5
    with pytest.raises(InputError, match="texture file not found"):
        avatar_albedo(anny_body, str(tmp_path / "none.png"))


def test_load_camera(tmp_path):
    f = tmp_path / "cam.json"
    f.write_text(json.dumps({"eye": [0, 1, 4], "target": [0, 1, 0], "fov_deg": 40}))
    cam = load_camera(f, (90, 160))
    assert cam.size == (90, 160)
    # The target projects to the image centre.
    px = cam.project(torch.tensor([[0.0, 1.0, 0.0]]))
    torch.testing.assert_close(px[0, 0], torch.tensor([80.0, 45.0]), atol=1e-3, rtol=0)
    for bad, text in (({"eye": [0, 1]}, "3 numbers"), ({"eye": [0, 1, 0], "target": [0, 1, 0]}, "coincide"),
                      ({"eye": [0, 1, 4], "fov_deg": 200}, "fov"), ({"target": [0, 0, 0]}, "eye"),
                      ({"eye": [0, 1, float("nan")]}, "finite")):
        f.write_text(json.dumps(bad))
        with pytest.raises(InputError, match=text):
            load_camera(f, (90, 160))
    with pytest.raises(InputError, match="not found"):
        load_camera(tmp_path / "none.json", (9, 9))
