"""`relightnet batch` at the command line: a bad jobs file is one line; the table; Ctrl-C's resume hint
(the runner itself: tests/distributed/test_batch.py)."""

from relightnet._cli.batch import _table
from relightnet.cli import build_parser, main


def test_a_bad_jobs_file_is_one_line(tmp_path, capsys):
    assert main(["batch", str(tmp_path / "jobs.yaml")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("relightnet batch: ") and "jobs.yaml" in err[0]
    (tmp_path / "jobs.yaml").write_text("jobs: 3\n")
    assert main(["batch", str(tmp_path / "jobs.yaml")]) == 1
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["jobs.yaml"]


def test_resume_hint_and_table():
    args = build_parser().parse_args(["batch", "work/jobs.yaml", "--ray"])
    assert args.ray == "" and args.interrupt_hint(args) == "run the same command again to resume work/jobs.yaml"
    summary = {"jobs": [
        {"index": 0, "command": "relight-image", "status": "done", "seconds": 1.25, "error": None, "out": "o/a.png"},
        {"index": 1, "command": "avatar", "status": "failed", "seconds": 0.5, "error": "x.mp4: not found",
         "out": "o/b.mp4"}],
        "counts": {"done": 1, "skipped": 0, "failed": 1, "pending": 2}}
    lines = _table(summary).splitlines()
    assert lines[0].split() == ["job", "command", "status", "seconds", "output", "or", "error"]
    assert lines[1].split() == ["0", "relight-image", "done", "1.2", "o/a.png"]
    assert lines[2].endswith("x.mp4: not found") and lines[-1] == "1 done, 0 skipped, 1 failed, 2 not run"
