"""``relightnet fit`` and the motion file it writes, read by render-body --motion."""

import numpy as np
import torch

from relightnet.cli import main
from relightnet.io import video_info, write_image


def test_no_person_is_one_line_and_nothing_written(tmp_path, capsys):
    img = tmp_path / "empty.png"
    write_image(img, torch.full((96, 128, 3), 0.5), srgb=False)
    out = tmp_path / "out" / "m.npz"
    assert main(["fit", str(img), "--out", str(out), "--preview", str(tmp_path / "out" / "p.png")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "empty.png: no person found" in err[0]
    assert not (tmp_path / "out").exists()


def test_bad_options_are_refused_before_work(tmp_path, capsys):
    img = tmp_path / "p.png"
    write_image(img, torch.zeros((16, 16, 3)), srgb=False)
    assert main(["fit", str(img), "--out", str(tmp_path / "m.npz"), "--preview", str(tmp_path / "p.mp4")]) == 1
    assert "--preview" in capsys.readouterr().err
    assert main(["fit", str(img), "--out", str(tmp_path / "m.json")]) == 1
    assert "--out" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.png"]


def test_render_body_reads_a_fitted_motion(tmp_path, anny_body, capsys):
    from relightnet.body import AnnyMotion, save_anny_motion

    T = 2
    pose = anny_body.pose("arms_down", T)
    pose[1, 0] = torch.tensor([0.0, 0.5, 0.0])
    m = AnnyMotion(pose, torch.zeros(T, 3), torch.tensor([0.5, 0.78, 0.5, 0.5, 0.37, 0.5]), anny_body.joint_names)
    save_anny_motion(tmp_path / "m.npz", m)
    assert main(["-q", "render-body", "--motion", str(tmp_path / "m.npz"), "--light", "studio", "--res", "48",
                 "--n-dirs", "8", "--out", str(tmp_path / "w.mp4")]) == 0
    assert video_info(tmp_path / "w.mp4").n_frames == T
    np.savez(tmp_path / "bad.npz", body_model=np.array("anny"), pose=np.zeros((2, 5, 3)),
             bone_names=np.array(list("abcde")), trans=np.zeros((2, 3)), phenotype=np.full(6, 0.5))
    assert main(["render-body", "--motion", str(tmp_path / "bad.npz"), "--light", "studio",
                 "--out", str(tmp_path / "b.mp4")]) == 1
    assert "key 'bone_names'" in capsys.readouterr().err


def test_avatar_motion_from_refuses_a_second_motion(tmp_path, capsys):
    src = tmp_path / "src.png"
    write_image(src, torch.zeros((16, 16, 3)), srgb=False)
    clip = tmp_path / "t.mp4"
    from relightnet.io import VideoWriter

    with VideoWriter(clip, fps=10) as w:
        for _ in range(2):
            w.write(np.zeros((16, 16, 3), np.uint8))
    assert main(["avatar", "--motion-from", str(src), "--motion", "walk", "--target", str(clip), "--light", "studio",
                 "--out", str(tmp_path / "o" / "a.mp4")]) == 1
    assert "--motion-from" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
