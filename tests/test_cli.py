"""relightnet.cli: every command's --help, the one error/interrupt/log behaviour, the entry points."""

from __future__ import annotations

import argparse
import logging
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from relightnet.cli import _leaf_parsers, build_parser, configure_logging, error_line, main

REPO = Path(__file__).resolve().parents[1]
ENV = dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND="Agg")


def _command_paths(parser=None, prefix=()) -> list[tuple[str, ...]]:
    """('light', 'show'), ('render',), ...: every command a user can type, nested ones included."""
    parser = parser or build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    out = []
    for name, p in sub.choices.items():
        nested = [a for a in p._actions if isinstance(a, argparse._SubParsersAction)]
        out += _command_paths(p, (*prefix, name)) if nested else [(*prefix, name)]
    return out


COMMANDS = _command_paths()
#: What particular help pages must say, beyond usage and examples.
MENTIONS = {
    ("synth",): ["N/8 and N/4", "--sequence T", "--verify data/synth"],
    ("smooth-light",): ["--outlier-eps", "OUT.lights.npz"],
    ("render-body",): ["--motion walk", "rest, tpose, apose, arms_down, arms_crossed", "walk, turn, idle, arm_raise",
                       "mask video"],
    ("blender-export",): ["relightnet blender-export --pose", "rest, tpose, apose, arms_down, arms_crossed"],
    ("blender-render",): ["relightnet blender-render avatar.blend"],
    ("avatar",): ["pooled", "walk, turn, idle, arm_raise"],
    ("train",): ["-m train", "--resume"],
    ("light", "show"): ["city, courtyard, forest"],
}


def test_every_command_is_listed_and_reached():
    assert len(COMMANDS) == len(_leaf_parsers(next(a for a in build_parser()._actions
                                                   if isinstance(a, argparse._SubParsersAction)))) >= 20
    assert all(m in COMMANDS for m in MENTIONS)


@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_help(command, capsys):
    """Each command's help: usage, examples that the parser accepts, no torch needed, status 0."""
    with pytest.raises(SystemExit) as e:
        main([*command, "--help"])
    out = capsys.readouterr().out
    assert e.value.code == 0 and out.startswith(f"usage: relightnet {' '.join(command)}")
    assert "--max-pixels" in out and "examples:" in out
    from relightnet.io.limits import DEFAULT_MAX_PIXELS

    assert f"{DEFAULT_MAX_PIXELS:,}" in " ".join(out.split())  # the default the code uses
    examples = out.split("examples:\n", 1)[1].splitlines()
    mine = [shlex.split(x.split("  # ")[0].split("# ")[0])[1:] for x in examples
            if x.strip().startswith(f"relightnet {' '.join(command)} ") or x.strip() == f"relightnet {command[0]}"]
    assert mine, "no example of the command itself"
    parser = build_parser()
    for argv in mine:
        args = parser.parse_args(argv)  # an example the parser refuses exits 2 here
        assert args.func is not None
    for text in MENTIONS.get(command, []):
        assert text in " ".join(out.split()), text


def test_top_level_help_lists_every_command(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    out = capsys.readouterr().out
    assert e.value.code == 0
    assert all(c[0] in out for c in COMMANDS)
    assert main([]) == 2 and main(["light"]) == 2  # no command: the help, status 2
    assert "usage: relightnet" in capsys.readouterr().out


@pytest.mark.parametrize("entry, cwd", [
    (["-m", "relightnet", "--help"], "any"),
    (["-m", "relightnet", "train", "--help"], "any"),
    (["-m", "train", "--help"], "repo"),
    (["-m", "export", "--help"], "repo"),
    (["-m", "export", "serve", "--help"], "repo"),
])
def test_entry_points(entry, cwd, tmp_path):
    """python -m relightnet from any folder; the thin train/ and export/ entry points from the repository root."""
    r = subprocess.run([sys.executable, *entry], capture_output=True, text=True, env=ENV,
                       cwd=tmp_path if cwd == "any" else REPO, timeout=120)
    assert r.returncode == 0, r.stderr
    command = {"train": "train", "export": "onnx-run" if "serve" in entry else "export"}.get(entry[1], None)
    first = r.stdout.splitlines()[0]
    assert first.startswith("usage: relightnet" + (f" {command}" if command else "")), first
    if entry[1] == "export" and "serve" not in entry:
        assert "--int8" in r.stdout
    bare = subprocess.run([sys.executable, "-m", "export"], capture_output=True, text=True, env=ENV, cwd=REPO,
                          timeout=120) if entry == ["-m", "export", "--help"] else None
    if bare is not None:
        assert bare.returncode == 2 and "python -m export serve" in bare.stderr


def test_error_line_is_one_line_for_input_errors_and_none_for_bugs(tmp_path):
    from relightnet.checks import InputError, ShapeError

    missing = FileNotFoundError(2, "No such file or directory", str(tmp_path / "masks"))
    assert error_line(missing) == f"FileNotFoundError: {tmp_path / 'masks'}: no such file or directory"
    assert error_line(InputError("a.png: bad\nsecond line")) == "InputError: a.png: bad"
    assert error_line(ShapeError("x: expected (3,)")) == "ShapeError: x: expected (3,)"
    assert error_line(ValueError("")) == "ValueError: ValueError"
    assert error_line(PermissionError("denied")) == "PermissionError: denied"
    assert error_line(KeyError("k")) is None and error_line(TypeError("bug")) is None


def test_an_output_that_cannot_be_made_is_refused_before_work(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    rc = main(["export", "--out", str(tmp_path / "file" / "m.onnx")])  # a parent that is a file
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1 and "cannot make its folder" in err[0]
    assert main(["export", "--out", str(tmp_path / "m.pt")]) == 1
    assert "expected a file ending in .onnx" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_logging_quiet_for_third_parties(capsys):
    def emit():
        logging.getLogger("relightnet.x").info("own info")
        logging.getLogger("relightnet.x").debug("own debug")
        logging.getLogger("onnxruntime.quantization").info("library info")
        logging.info("root info")  # what libraries that log through the logging module's functions do
        logging.getLogger("some_library").warning("library warning")  # (ray, once imported, has its own handler)
        return capsys.readouterr().err

    try:
        configure_logging()
        err = emit()
        assert "own info" in err and "library warning" in err
        assert "own debug" not in err and "library info" not in err and "root info" not in err
        configure_logging(verbose=True)
        err = emit()
        assert all(m in err for m in ("own info", "own debug", "library info", "root info"))
        configure_logging(quiet=True)
        assert emit().strip() == "WARNING some_library: library warning"
    finally:
        logging.basicConfig(level=logging.WARNING, force=True)


@pytest.mark.slow
def test_ctrl_c_in_train_is_one_line_with_the_resume_hint(tmp_path, tiny_dataset):
    """A real SIGINT to the process group (as a terminal sends it) while the model trains."""
    config = tmp_path / "long.yaml"
    config.write_text((REPO / "train/configs/tiny.yaml").read_text().replace("steps: 6", "steps: 100000"))
    run = tmp_path / "runs" / "x"
    # A terminal's Ctrl-C reaches a process whose SIGINT is handled; a runner that starts the suite in the
    # background (nohup, `cmd &`, some CI) hands SIGINT down ignored, and Python keeps it ignored: restore it.
    child = subprocess.Popen([sys.executable, "-m", "relightnet", "train", "--config", str(config), "--data",
                              str(tiny_dataset), "--out", str(run)], env=ENV, start_new_session=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        end = time.monotonic() + 300
        while not (run / "metrics.jsonl").exists() and child.poll() is None and time.monotonic() < end:
            time.sleep(0.02)
        assert child.poll() is None, child.communicate()[1]
        os.killpg(child.pid, signal.SIGINT)
        _, err = child.communicate(timeout=120)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    assert child.returncode == 130
    assert err.strip().splitlines()[-1] == (f"relightnet train: interrupted; run the same command with --resume to "
                                            f"continue from {run}/last.pt")
    assert "Traceback" not in err


@pytest.mark.slow
def test_sigterm_is_as_clean_as_ctrl_c(tmp_path, masked_clip):
    """A real SIGTERM (what `kill`, systemd and container runtimes send) while relight-video writes:
    one line, status 143, no temporary file and no folder the command made."""
    video, masks = masked_clip(tmp_path, n=400)
    out_dir = tmp_path / "new" / "deeper"
    child = subprocess.Popen([sys.executable, "-m", "relightnet", "relight-video", str(video), "--masks", str(masks),
                              "--light", "studio", "--out", str(out_dir / "r.mp4")], env=ENV,
                             preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        end = time.monotonic() + 300
        while not (out_dir.is_dir() and any(out_dir.iterdir())) and child.poll() is None and time.monotonic() < end:
            time.sleep(0.02)
        assert child.poll() is None, child.communicate()[1]
        time.sleep(0.5)  # frames are being written to the hidden temporary file
        child.send_signal(signal.SIGTERM)
        _, err = child.communicate(timeout=120)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    assert child.returncode == 143, err
    assert err.strip().splitlines()[-1] == "relightnet relight-video: terminated"
    assert not (tmp_path / "new").exists()


@pytest.mark.slow
def test_commands_leave_nothing_in_the_temp_folder(tmp_path):
    """ONNX Runtime's telemetry (``.ses``) and torch's kernel cache (``torchinductor_<user>/``, made by
    ``import torch._dynamo``) are kept out of a fresh temp folder."""
    tmp, home = tmp_path / "tmp", tmp_path / "home"
    tmp.mkdir()
    home.mkdir()
    env = {k: v for k, v in ENV.items() if k not in ("TORCHINDUCTOR_CACHE_DIR", "ORT_DISABLE_TELEMETRY",
                                                      "XDG_CACHE_HOME")}
    env.update(TMPDIR=str(tmp), HOME=str(home))
    photo = tmp_path / "p.png"
    subprocess.run([sys.executable, "-c", "import numpy as np; from relightnet.io import write_image; "
                    f"write_image({str(photo)!r}, np.full((64, 48, 3), 128, np.uint8))"], env=ENV, check=True,
                   timeout=120)
    for argv, rc in ((["segment", str(photo), "--out", str(tmp_path / "m.png")], 1),  # ONNX Runtime ran: nobody
                     (["render-body", "--light", "studio", "--res", "32", "--n-dirs", "8",
                       "--out", str(tmp_path / "b.png")], 0)):  # roma, hence torch._dynamo
        r = subprocess.run([sys.executable, "-m", "relightnet", "-q", *argv], capture_output=True, text=True,
                           env=env, cwd=tmp_path, timeout=300)
        assert r.returncode == rc and (rc == 0 or "no person found" in r.stderr), r.stderr
        assert sorted(p.name for p in tmp.iterdir()) == [], argv
