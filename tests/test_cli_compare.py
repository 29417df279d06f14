"""`relightnet compare` at the command line: inputs and the report folder checked before any work (runs:
tests/pipeline/test_compare.py)."""

import pytest

from relightnet.cli import build_parser, main
from relightnet.names import VIDEO_SMOOTHING as SMOOTHING

pytestmark = pytest.mark.slow  # the compare command end to end


def test_missing_data_and_a_file_for_the_report_folder(tmp_path, capsys):
    assert main(["compare", "--data", str(tmp_path / "seq"), "--out", str(tmp_path / "r")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--data" in err[0] and "seq: not found" in err[0]
    (tmp_path / "seq").mkdir()
    (tmp_path / "r").write_text("")
    assert main(["compare", "--data", str(tmp_path / "seq"), "--out", str(tmp_path / "r")]) == 1
    assert "is a file; expected a folder" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r", "seq"]


def test_options():
    a = build_parser().parse_args(["compare", "--data", "d", "--out", "r", "--backend", "onnx", "--clips", "2"])
    assert (a.backend, a.clips, a.smoothing, a.split, a.n_dirs) == ("onnx", 2, "auto", "test", 64)
    assert set(SMOOTHING) == set(next(x for x in build_parser()._subparsers._group_actions[0].choices["compare"]
                                      ._actions if x.dest == "smoothing").choices)
