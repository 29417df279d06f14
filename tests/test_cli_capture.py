"""``relightnet capture``: a person into an avatar file; ``render-body --avatar`` and ``avatar --avatar`` use it."""

import numpy as np
import pytest
import torch

from relightnet.cli import main
from relightnet.io import VideoWriter, read_image, read_video, video_info, write_image


def test_no_person_is_one_line_and_nothing_written(tmp_path, capsys):
    clip = tmp_path / "empty.mp4"
    with VideoWriter(clip, fps=10) as w:
        for _ in range(3):
            w.write(np.full((96, 96, 3), 120, np.uint8))
    out = tmp_path / "out" / "me.avatar.npz"
    assert main(["capture", str(clip), "--out", str(out), "--preview", str(tmp_path / "out" / "s.png")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "empty.mp4" in err[0]
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_bad_options_are_refused_before_work(tmp_path, capsys):
    img = tmp_path / "p.png"
    write_image(img, torch.zeros((16, 16, 3)), srgb=False)
    for extra, what in ((["--out", str(tmp_path / "me.npz")], ".avatar.npz"),
                        (["--out", str(tmp_path / "me.avatar.npz"), "--reproject", str(tmp_path / "r.mp4")],
                         "--reproject"),
                        (["--out", str(tmp_path / "me.avatar.npz"), "--texture-size", "10"], "texture size")):
        assert main(["capture", str(img), *extra]) == 1
        assert what in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.png"]


@pytest.fixture(scope="module")
def photo_capture(tmp_path_factory, anny_body):
    """A generated person photographed from the front, captured (a photo: the front only, no offsets)."""
    from relightnet.capture.truth import light_pair, turning_person

    d = tmp_path_factory.mktemp("photo")
    clip = turning_person(d, anny_body, light_pair()[0], n_frames=2, size=(320, 256), seed=11, turns=0.0,
                          texture_size=256)
    photo = d / "person.png"
    write_image(photo, next(iter(read_video(clip.video))), srgb=False)
    out = d / "me.avatar.npz"
    code = main(["-q", "capture", str(photo), "--out", str(out), "--texture-size", "256", "--preview",
                 str(d / "sheet.png"), "--reproject", str(d / "reproj.png"), "--mask-out", str(d / "mask.png")])
    return d, code, out


@pytest.mark.slow
def test_a_photo_is_captured_front_only(photo_capture, anny_body):
    from relightnet.capture import load_avatar

    d, code, out = photo_capture
    assert code == 0
    av = load_avatar(out, anny_body.num_verts)
    assert 0.25 < av.seen_share < 0.7  # one side of the body
    assert float(av.offsets.abs().max()) == 0.0 and av.frames == 1
    sheet = read_image(d / "sheet.png")
    assert sheet.shape[0] == 384 and sheet.shape[1] == 2 * 384 + 4 * 288
    mask = read_image(d / "mask.png")[..., 0] > 0.5
    assert 0.03 < float(mask.float().mean()) < 0.5
    assert (d / "reproj.png").is_file()


@pytest.mark.slow
def test_render_body_and_avatar_take_the_capture(photo_capture, tmp_path, capsys):
    d, code, out = photo_capture
    assert main(["-q", "render-body", "--avatar", str(out), "--pose", "apose", "--light", "studio", "--res", "64",
                 "--n-dirs", "8", "--out", str(tmp_path / "me.png")]) == 0
    img = read_image(tmp_path / "me.png")
    assert img.shape[:2] == (64, 64) and float(img.amax()) > 0.1
    clip = tmp_path / "target.mp4"
    with VideoWriter(clip, fps=10) as w:
        for _ in range(2):
            w.write(np.full((64, 48, 3), 90, np.uint8))
    assert main(["-q", "avatar", "--avatar", str(out), "--target", str(clip), "--light", "studio", "--motion", "walk",
                 "--n-dirs", "8", "--out", str(tmp_path / "a.mp4")]) == 0
    assert video_info(tmp_path / "a.mp4").n_frames == 2
    assert main(["avatar", "--avatar", str(out), "--outfit", "casual", "--target", str(clip), "--light", "studio",
                 "--out", str(tmp_path / "b.mp4")]) == 1
    assert "drop --outfit" in capsys.readouterr().err
    bad = tmp_path / "bad.avatar.npz"
    bad.write_bytes(b"junk")
    assert main(["render-body", "--avatar", str(bad), "--light", "studio", "--out", str(tmp_path / "x.png")]) == 1
    assert "bad.avatar.npz" in capsys.readouterr().err
