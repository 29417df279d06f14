"""`relightnet relight-image` / `relight-video` at the command line: the output rule and input checks
before any work (runs: tests/pipeline/test_relight_image.py, test_relight_video.py)."""

import torch

from relightnet.cli import main


def _one_line(capsys, rc):
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1, err
    return err[0]


def test_relight_video_checks_before_work(tmp_path, capsys):
    line = _one_line(capsys, main(["relight-video", str(tmp_path / "clip.mp4"), "--light", "studio", "--out",
                                   str(tmp_path / "r.png")]))
    assert "expected a file ending in .mp4, .mkv" in line
    line = _one_line(capsys, main(["relight-video", str(tmp_path / "clip.mp4"), "--light", "studio", "--out",
                                   str(tmp_path / "new" / "r.mp4")]))
    assert "clip.mp4: not found" in line
    (tmp_path / "clip.mp4").write_bytes(b"")
    line = _one_line(capsys, main(["relight-video", str(tmp_path / "clip.mp4"), "--masks", str(tmp_path / "m"),
                                   "--light", "studio", "--out", str(tmp_path / "new" / "r.mp4")]))
    assert "--masks" in line and "m: not found" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.mp4"]


def test_relight_image_checks_before_work(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    line = _one_line(capsys, main(["relight-image", str(tmp_path / "p.jpg"), "--light", "sunset", "--out",
                                   str(tmp_path / "file" / "r.png")]))
    assert "cannot make its folder" in line
    line = _one_line(capsys, main(["relight-image", str(tmp_path / "p.jpg"), "--light", "sunset", "--out",
                                   str(tmp_path / "r.png"), "--save-maps", str(tmp_path / "file")]))
    assert "--save-maps" in line and "is a file; expected a folder" in line
    line = _one_line(capsys, main(["relight-image", str(tmp_path / "p.jpg"), "--light", "sunset", "--out",
                                   str(tmp_path / "out" / "r.png")]))
    assert "p.jpg" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_a_light_sequence_for_one_light_is_an_input_error(tmp_path, capsys):
    """--light takes one light: a (T, K, 3) sequence is refused in one line naming the option (an
    InputError, not a ValueError)."""
    import numpy as np
    import torch

    from relightnet.io import write_image
    from relightnet.sh import save_light_sequence

    write_image(tmp_path / "p.png", np.full((32, 32, 3), 128, np.uint8), srgb=False)
    write_image(tmp_path / "m.png", np.full((32, 32, 3), 255, np.uint8), srgb=False)
    save_light_sequence(tmp_path / "seq.npz", torch.zeros(4, 9, 3))
    line = _one_line(capsys, main(["relight-image", str(tmp_path / "p.png"), "--mask", str(tmp_path / "m.png"),
                                   "--light", str(tmp_path / "seq.npz"), "--out", str(tmp_path / "r.png")]))
    assert "InputError: --light" in line and "expected one light (K, 3), got a sequence (4, 9, 3)" in line
    assert not (tmp_path / "r.png").exists()


def test_an_output_equal_to_the_input_is_refused_and_the_original_kept(tmp_path, capsys):
    from relightnet.io import write_image

    photo = write_image(tmp_path / "p.png", torch.full((20, 24, 3), 0.5))
    before = photo.read_bytes()
    for cmd in (["relight-image", str(photo), "--light", "studio", "--out", str(photo)],
                ["relight-video", str(photo), "--light", "studio", "--out", str(tmp_path / "p.mp4")],
                ["segment", str(photo), "--out", str(photo)]):
        if cmd[0] == "relight-video":
            (tmp_path / "p.mp4").write_bytes(b"not a video")
            cmd[1] = str(tmp_path / "p.mp4")
            before_video = (tmp_path / "p.mp4").read_bytes()
        line = _one_line(capsys, main(cmd))
        assert "is the input" in line, (cmd, line)
    assert photo.read_bytes() == before and (tmp_path / "p.mp4").read_bytes() == before_video


def test_a_display_p3_photo_gives_a_display_p3_output(tmp_path):
    """relight-image carries the photo's ICC profile to its PNG (io.icc)."""
    import numpy as np
    from PIL import Image

    from relightnet.io import write_image
    from relightnet.io.icc import read_icc

    from .io.icc_profiles import display_p3

    icc = display_p3()
    Image.fromarray(np.full((48, 40, 3), (200, 120, 90), np.uint8)).save(tmp_path / "p.png", icc_profile=icc)
    write_image(tmp_path / "m.png", np.full((48, 40, 3), 255, np.uint8), srgb=False)
    assert main(["-q", "relight-image", str(tmp_path / "p.png"), "--mask", str(tmp_path / "m.png"),
                 "--light", "studio", "--out", str(tmp_path / "r.png")]) == 0
    assert read_icc(tmp_path / "r.png") == icc
