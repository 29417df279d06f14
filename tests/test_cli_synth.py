import json
import os

import pytest

from relightnet._cli.synth import build_config
from relightnet.cli import build_parser, main
from relightnet.io import read_image

TINY = ["--res", "32", "--n-dirs", "16", "--shard-size", "2", "--workers", "0"]


def _cfg(*argv):
    return build_config(build_parser().parse_args(["synth", "--out", "x", *argv]))


def test_ctrl_c_hint_names_the_folder():
    args = build_parser().parse_args(["synth", "--out", "data/big", "--count", "10"])
    assert args.interrupt_hint(args) == "run the same command again to resume data/big"


def test_count_rules_and_config_file(tmp_path):
    assert _cfg().counts == {"train": 64, "val": 8, "test": 16}
    assert _cfg("--count", "100").counts == {"train": 100, "val": 13, "test": 25}
    assert _cfg("--count", "3", "--split-count", "test=0").counts == {"train": 3, "val": 1, "test": 0}
    (tmp_path / "c.yaml").write_text("res: 64\ncounts: {train: 10, val: 10, test: 0}\nn_dirs: 32\n")
    c = _cfg("--config", str(tmp_path / "c.yaml"), "--count", "20", "--seed", "4", "--sequence", "3")
    assert (c.res, c.n_dirs, c.seed, c.sequence_frames) == (64, 32, 4, 3)
    assert c.counts == {"train": 20, "val": 20, "test": 0}
    assert _cfg("--config", str(tmp_path / "c.yaml"), "--res", "96").res == 96


@pytest.mark.slow
def test_make_verify_preview(tmp_path, capsys):
    d = tmp_path / "data" / "ds"  # missing parent folders are made, as for every command's output
    argv = ["-q", "synth", "--out", str(d), "--count", "2", "--split-count", "val=0", "--split-count", "test=1", *TINY]
    assert main(argv) == 0
    m = json.loads((d / "manifest.json").read_text())
    assert m["complete"] and m["config"]["counts"] == {"train": 2, "val": 0, "test": 1}
    assert main(argv) == 0  # nothing to do: checked and kept
    assert main(["synth", "--verify", str(d)]) == 0
    assert f"{d}: ok (2 shards; train 2, test 1 samples)" in capsys.readouterr().out
    assert main(["-q", "synth", "--preview", str(d), "--out", str(tmp_path / "sheets" / "sheet.png"), "--n", "2"]) == 0
    assert read_image(tmp_path / "sheets" / "sheet.png").shape == (64, 320, 3)
    # A damaged shard: one line per problem, exit 1.
    p = d / "test-00000.npz"
    data = bytearray(p.read_bytes())
    data[100] ^= 1
    p.write_bytes(bytes(data))
    assert main(["synth", "--verify", str(d)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"{p}: sha256 mismatch (corrupted or changed)"]
    # Resuming with other settings is refused, and nothing changes.
    before = {q.name: os.stat(q).st_mtime_ns for q in d.iterdir()}
    assert main(["synth", "--out", str(d), "--count", "2", *TINY[:2], "--n-dirs", "32"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "n_dirs: 16 there, 32 now" in err[0]
    assert {q.name: os.stat(q).st_mtime_ns for q in d.iterdir()} == before


@pytest.mark.parametrize("argv, message", [
    (["--out", "{t}/ds", "--res", "100"], "config res: expected a multiple of 16 from 16 to 4096, got 100"),
    (["--out", "{t}/ds", "--count", "-3"], "--count: expected an integer >= 0, got -3"),
    (["--out", "{t}/ds", "--split-count", "val=-1"], "--split-count val: expected an integer >= 0"),
    (["--out", "{t}/ds", "--workers", "-1"], "--workers: expected an integer >= 0"),
    (["--out", "{t}/ds", "--splits", "train,dev"], "splits: expected names from"),
    (["--out", "{t}/no/such/ds", "--splits", "train,dev"], "splits: expected names from"),  # made folders removed
    (["--out", "{t}/f/ds", "--count", "-3"], "--count: expected an integer >= 0, got -3"),
    (["--out", "{t}/ds", "--config", "{t}/missing.yaml"], "config file not found"),
    (["--verify", "{t}/none"], "{t}/none: dataset folder not found"),
    (["--preview", "{t}/none"], "{t}/none: dataset folder not found"),
    ([], "--out: a dataset folder is required"),
    (["--verify", "{t}/d", "--count", "3"], "--count: not used with --verify"),  # honoured or refused
    (["--preview", "{t}/d", "--res", "32", "--seed", "1"], "--res, --seed: not used with --preview"),
    (["--out", "{t}/d", "--n", "4", "--split", "val"], "--n, --split: not used with making a dataset"),
    (["--out", "{t}/d", "--cpus-per-task", "2"], "--cpus-per-task: not used with making a dataset"),
    (["--out", "{t}/d", "--ray", "--workers", "2"], "--workers: not used with --ray"),
])
def test_bad_inputs_fail_cleanly(tmp_path, capsys, argv, message):
    argv = [a.format(t=tmp_path) for a in argv]
    making = "--out" in argv and "--workers" not in argv and "--preview" not in argv
    assert main(["synth", *argv, "--workers", "0"] if making else ["synth", *argv]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message.format(t=tmp_path) in err[0], err
    assert list(tmp_path.iterdir()) == []
