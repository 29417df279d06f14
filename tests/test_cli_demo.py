"""`relightnet demo` at the command line: sizes and the output folder checked before any work (the run:
tests/pipeline/test_demo.py)."""

import pytest

from relightnet.cli import main

pytestmark = pytest.mark.slow  # the demo end to end


def test_bad_sizes_and_outputs_fail_in_one_line(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path / "d"), "--size", "100"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--size: expected a multiple of 16, got 100" in err[0]
    assert main(["demo", "--out", str(tmp_path / "d"), "--compare-size", "40"]) == 1
    assert "--compare-size: expected a multiple of 16, got 40" in capsys.readouterr().err
    (tmp_path / "f").write_text("")
    assert main(["demo", "--out", str(tmp_path / "f")]) == 1
    assert "--out" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f"]
