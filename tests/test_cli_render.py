
import numpy as np
import pytest
import trimesh

from relightnet.cli import main
from relightnet.io import read_image, read_video, video_info


def test_render_mesh_file(tmp_path):
    trimesh.creation.icosphere(2).export(tmp_path / "s.obj")
    assert main(["-q", "render", str(tmp_path / "s.obj"), "--light", "studio", "--res", "48", "--n-dirs", "32",
                 "--out", str(tmp_path / "s.png"), "--save-maps", str(tmp_path / "maps")]) == 0
    img = read_image(tmp_path / "s.png")
    assert img.shape == (48, 48, 3) and img.max() > 0.3
    maps = np.load(tmp_path / "maps" / "maps.npz")
    assert maps["transport"].shape == (48, 48, 9) and maps["mask"].sum() > 100


@pytest.mark.slow
def test_render_body_still_and_motion(tmp_path):
    assert main(["-q", "render-body", "--pose", "arms_crossed", "--light", "sunset", "--res", "64", "--n-dirs", "16",
                 "--out", str(tmp_path / "b.png"), "--mask-out", str(tmp_path / "m.png")]) == 0
    m = read_image(tmp_path / "m.png")
    assert m.shape == (64, 64, 3) and 0.02 < m.mean() < 0.5
    assert main(["-q", "render-body", "--motion", "walk", "--frames", "3", "--light", "studio", "--res", "64",
                 "--n-dirs", "8", "--out", str(tmp_path / "w.mp4"), "--mask-out", str(tmp_path / "wm.mkv")]) == 0
    info = video_info(tmp_path / "w.mp4")
    assert info.n_frames == 3 and info.size == (64, 64)
    masks = np.stack(list(read_video(tmp_path / "wm.mkv")))  # --mask-out with --motion: a lossless mask video
    assert masks.shape == (3, 64, 64, 3) and 0.02 < (masks > 127).mean() < 0.5 and masks.max() == 255
    # a still body's mask is an image, a motion's a video: the other is refused before any work
    assert main(["render-body", "--motion", "walk", "--light", "studio", "--out", str(tmp_path / "v" / "w.mp4"),
                 "--mask-out", str(tmp_path / "v" / "m.png")]) == 1
    assert not (tmp_path / "v").exists()


def test_bad_inputs_fail_cleanly(tmp_path, capsys):
    out = tmp_path / "x.png"
    assert main(["render", str(tmp_path / "missing.obj"), "--light", "studio", "--out", str(out)]) == 1
    assert "missing.obj: mesh file not found" in capsys.readouterr().err
    trimesh.creation.box().export(tmp_path / "b.obj")
    assert main(["render", str(tmp_path / "b.obj"), "--light", "no_such_light", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "no_such_light" in err and len(err.strip().splitlines()) == 1
    assert main(["render-body", "--motion", "walk", "--light", "studio", "--out", str(out)]) == 1
    assert "renders a video" in capsys.readouterr().err
    assert main(["render-body", "--motion", "clip.npz", "--light", "studio", "--out", str(tmp_path / "c.mp4")]) == 1
    assert "SMPL-style motion files drive an SMPL body" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        main(["render-body", "--phenotype", "height", "--light", "studio", "--out", str(out)])
    assert e.value.code == 2
    assert list(tmp_path.iterdir()) == [tmp_path / "b.obj"]
