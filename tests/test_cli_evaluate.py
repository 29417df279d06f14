"""``relightnet evaluate REPORT``: each report parses its own options and refuses the others' (no torch needed)."""

import pytest

from relightnet.cli import build_parser, main

#: Each report, the smallest command line it parses, and the options of other reports it refuses.
REPORTS = {
    "data": (["--data", "d"], ["--clips", "c"], ["--photos", "p"], ["--frames", "2"]),
    "light": (["--data", "d", "--clips", "a", "b"], ["--as-photo"], ["--no-baseline"], ["--ablation", "x.pt"]),
    "photos": (["photos/"], ["--data", "d"], ["--split", "val"], ["--clips", "c"]),
    "fit": (["--clips", "1", "--frames", "2", "--res", "128"], ["--checkpoint", "x.pt"], ["--data", "d"],
            ["--texture", "64"]),
    "capture": (["--clips", "1", "--texture", "64"], ["--data", "d"], ["--split", "val"], ["--as-photo"]),
    "ship": (["shipped", "c.pt", "--data", "d", "--clips", "c", "--photos", "p"], ["--checkpoint", "x.pt"],
             ["--split", "val"], ["--as-photo"]),
}


@pytest.mark.parametrize("report", sorted(REPORTS))
def test_each_report_parses_its_options_and_refuses_the_others(report, capsys):
    parser = build_parser()
    ok, *others = REPORTS[report]
    args = parser.parse_args(["evaluate", report, *ok])
    assert args.command == "evaluate" and args.report == report and args.func.__name__ == f"run_{report}"
    assert args.out == "out/evaluate"
    for option in others:
        with pytest.raises(SystemExit):
            parser.parse_args(["evaluate", report, *ok, *option])
        assert f"unrecognized arguments: {option[0]}" in capsys.readouterr().err


def test_the_reports_defaults_and_their_own_options():
    parser = build_parser()
    fit = parser.parse_args(["evaluate", "fit"])
    assert (fit.clips, fit.frames, fit.res) == (3, 12, 256)
    cap = parser.parse_args(["evaluate", "capture"])
    assert (cap.clips, cap.frames, cap.res, cap.texture, cap.device) == (2, 48, 256, 512, "cpu")
    light = parser.parse_args(["evaluate", "light", "--data", "d", "--clips", "a", "b"])
    assert light.clips == ["a", "b"] and light.split == "test"
    ship = parser.parse_args(["evaluate", "ship", "shipped", "c.pt", "--data", "d", "--clips", "c", "--photos", "p"])
    assert (ship.incumbent, ship.candidate, ship.clips) == ("shipped", "c.pt", "c")


@pytest.mark.parametrize("argv", [["evaluate", "data"], ["evaluate", "light"], ["evaluate", "ship", "shipped"],
                                  ["evaluate", "photos"], ["evaluate", "--photos", "p"], ["evaluate", "stills"]])
def test_a_report_without_what_it_needs_is_a_usage_error(argv, capsys):
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2 and "error:" in capsys.readouterr().err


def test_evaluate_alone_prints_the_reports(capsys):
    assert main(["evaluate"]) == 2
    out = capsys.readouterr().out
    assert all(f"relightnet evaluate {r} " in out for r in REPORTS)


def test_the_cheap_reports_fail_in_one_line_before_any_work(tmp_path, capsys):
    out = tmp_path / "new" / "rep"
    assert main(["evaluate", "photos", str(tmp_path), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("relightnet evaluate: ") and "no photos" in err and err.count("\n") == 1
    assert main(["evaluate", "ship", "shipped", str(tmp_path / "x.pt"), "--data", str(tmp_path), "--clips",
                 str(tmp_path), "--photos", str(tmp_path), "--out", str(out)]) == 1
    assert "no photos" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()
