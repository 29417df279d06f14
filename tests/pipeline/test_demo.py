from relightnet.cli import main
from relightnet.io import read_image, video_info
from relightnet.sh import preset_names


def test_demo_runs_on_embedded_defaults(tmp_path):
    out = tmp_path / "demo"
    assert main(["-q", "demo", "--out", str(out), "--size", "64", "--frames", "3", "--n-dirs", "8"]) == 0
    assert sorted(p.stem for p in (out / "lights").iterdir()) == sorted(preset_names())
    photo = read_image(out / "estimate" / "target_photo.png")
    pair = read_image(out / "estimate" / "avatar_true_vs_estimated_light.png")
    assert photo.shape == (64, 64, 3) and pair.shape == (64, 128, 3)
    assert pair[:, :64].max() > 0.2 and pair[:, 64:].max() > 0.05  # both renders show the avatar
    info = video_info(out / "avatar_walk.mp4")
    assert info.n_frames == 3 and info.size == (64, 64)
