"""`relightnet avatar` at the command line: inputs and outputs checked before any work (runs: tests/pipeline)."""

import pytest

from relightnet.cli import build_parser, main
from relightnet.names import VIDEO_SMOOTHING as SMOOTHING

pytestmark = pytest.mark.slow  # the avatar command end to end


def _one_line(capsys, rc):
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1, err
    return err[0]


def test_missing_inputs_are_one_line_before_any_work(tmp_path, capsys):
    out = tmp_path / "new" / "a.mp4"
    line = _one_line(capsys, main(["avatar", "--target", str(tmp_path / "clip.mp4"), "--target-masks",
                                   str(tmp_path / "masks"), "--out", str(out)]))
    assert line.startswith("relightnet avatar: InputError: --target-masks") and "masks: not found" in line
    line = _one_line(capsys, main(["avatar", "--target", str(tmp_path / "clip.mp4"), "--plate",
                                   str(tmp_path / "plate.mp4"), "--out", str(out)]))
    assert "--plate" in line and "plate.mp4: not found" in line
    line = _one_line(capsys, main(["avatar", "--target", str(tmp_path / "clip.mp4"), "--out", str(out)]))
    assert "clip.mp4" in line  # the target itself, before the model is loaded
    assert list(tmp_path.iterdir()) == []  # the output folder the rule made was removed again


def test_the_output_must_be_a_video(tmp_path, capsys):
    line = _one_line(capsys, main(["avatar", "--target", "x.mp4", "--out", str(tmp_path / "a.png")]))
    assert "--out" in line and "expected a file ending in .mp4, .mkv" in line


def test_smoothing_and_motion_choices():
    parser = build_parser()
    for name in SMOOTHING:
        assert parser.parse_args(["avatar", "--target", "t.mp4", "--out", "a.mp4", "--smoothing", name]).smoothing \
            == name
    with pytest.raises(SystemExit):
        parser.parse_args(["avatar", "--target", "t.mp4", "--out", "a.mp4", "--smoothing", "kalman"])
    a = parser.parse_args(["avatar", "--target", "t.mp4", "--out", "a.mp4"])
    # --motion unset (None) means walk, unless --motion-from gives the motion
    assert (a.motion, a.smoothing, a.backend, a.mask_source) == (None, "auto", "torch", "segment")
