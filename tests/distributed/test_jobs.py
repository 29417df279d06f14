import pytest

from relightnet.checks import InputError
from relightnet.cli import build_parser, command_table
from relightnet.distributed.jobs import _why, batchable_commands, load_jobs


def test_batchable_commands_are_the_cli_table():
    parser = build_parser()
    table = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction").choices
    assert list(command_table(parser)) == list(table)
    assert batchable_commands(table) == [c for c in table if c != "batch"]
    assert {"relight-image", "relight-video", "avatar", "estimate-light", "render-body"} <= set(
        batchable_commands(table))


def test_entries_are_checked_one_by_one(tmp_path):
    f = tmp_path / "jobs.yaml"
    f.write_text("""
jobs:
  - {command: relight-image, args: [p.png, --light, studio, --out, out/a.png], resources: {cpus: 2}, note: kept}
  - {command: relight-imag, args: [p.png, --out, out/b.png]}
  - {command: relight-image, args: [p.png, --light, studio]}
  - {command: relight-image, args: "p.png --out x.png"}
  - {command: estimate-light, args: [p.png, --out, out/l.npz], resources: {cpus: 0}}
  - {command: relight-image, args: [q.png, --light, sunset, --out, out/a.png]}
  - {command: render-body, args: [--frames, 10, --light, city, --out, out/w.mp4, --motion, walk], resources: {gpus: 1}}
  - just a string
""")
    jobs = load_jobs(f, command_table())
    assert [j.error for j in jobs[:1] + jobs[6:7]] == [None, None]
    assert jobs[0].out == "out/a.png" and jobs[0].cpus == 2 and jobs[0].extra == {"note": "kept"}
    assert jobs[6].args == ("--frames", "10", "--light", "city", "--out", "out/w.mp4", "--motion", "walk")
    assert jobs[6].gpus == 1
    assert jobs[1].error.startswith("unknown command 'relight-imag': expected one of light, render, ")
    assert jobs[2].error == "the following arguments are required: --out"
    assert jobs[3].error.startswith("args: expected a list of strings as on the command line")
    assert jobs[4].error == "resources.cpus: expected a number > 0, got 0"
    assert jobs[5].error == "--out out/a.png: job 0 writes it too"
    assert jobs[7].error == "expected a mapping with command and args, got str"


@pytest.mark.parametrize("text, match", [
    (None, "jobs file not found"),
    ("jobs: [", "unreadable jobs file"),
    ("- {command: light}", "expected a mapping with a 'jobs' list"),
])
def test_bad_jobs_files(tmp_path, text, match):
    f = tmp_path / "jobs.yaml"
    if text is not None:
        f.write_text(text)
    with pytest.raises(InputError, match=match):
        load_jobs(f, command_table())


def test_why_a_job_failed():
    assert _why("", -9, "avatar") == ("killed by SIGKILL", False)
    # The CLI's own one-line error is bad input: not worth a retry.
    assert _why("frame 1\rframe 2\nrelightnet avatar: InputError: in.mp4: no such file\n", 1, "avatar") == (
        "InputError: in.mp4: no such file", True)
    # A crash (a traceback's last line) is worth a retry.
    assert _why("Traceback ...\nMemoryError: out of memory\n", 1, "avatar") == ("MemoryError: out of memory", False)
