"""relightnet._cli's shared helpers (argtypes, paths, options, inputs): the output-path
rule, input checks and argument types shared by every command."""

import argparse
from pathlib import Path

import pytest
import torch

from relightnet._cli import argtypes, inputs, options, paths
from relightnet.checks import InputError
from relightnet.cli import main
from relightnet.sh import save_light


def test_out_file_makes_missing_parents_and_checks_the_type(tmp_path):
    p = paths.out_file(tmp_path / "a" / "b" / "x.mp4", suffixes=(".mp4", ".mkv"))
    assert p == tmp_path / "a" / "b" / "x.mp4" and p.parent.is_dir() and not p.exists()
    assert paths.out_file(str(tmp_path / "y.PNG"), suffixes=(".png",)).name == "y.PNG"  # any case
    with pytest.raises(InputError, match=r"--mask-out .*m.png: expected a file ending in .mp4, .mkv"):
        paths.out_file(tmp_path / "m.png", "--mask-out", (".mp4", ".mkv"))
    with pytest.raises(InputError, match="is a folder; expected a file path"):
        paths.out_file(tmp_path / "a")
    (tmp_path / "f").write_text("")
    with pytest.raises(InputError, match="cannot make its folder"):
        paths.out_file(tmp_path / "f" / "x.png")


def test_out_file_never_names_an_input(tmp_path):
    photo = tmp_path / "p.png"
    photo.write_bytes(b"x")
    for same in (photo, tmp_path / "." / "p.png"):
        with pytest.raises(InputError, match=r"--out .*p.png: is the input .*p.png; write the result to another"):
            paths.out_file(same, inputs=(None, photo))
    (tmp_path / "link.png").symlink_to(photo)
    with pytest.raises(InputError, match="is the input"):
        paths.out_file(tmp_path / "link.png", inputs=(photo,))
    (tmp_path / "hard.png").hardlink_to(photo)
    with pytest.raises(InputError, match="is the input"):
        paths.out_file(tmp_path / "hard.png", inputs=(photo,))
    assert paths.out_file(tmp_path / "q.png", inputs=(photo, "sunset", tmp_path)) == tmp_path / "q.png"


def test_out_dir_and_the_removal_of_folders_a_failed_command_made(tmp_path):
    with pytest.raises(RuntimeError), paths.made_folders() as made:  # a command that fails
        d = paths.out_dir(tmp_path / "n1" / "n2" / "run", "--out-dir")
        assert d.parent.is_dir() and not d.exists()  # the folder itself is the command's to make
        (tmp_path / "kept").mkdir()
        paths.out_file(tmp_path / "kept" / "n3" / "x.png")
        (tmp_path / "kept" / "n3" / "partial.txt").write_text("")  # something the command wrote: kept
        assert made == [tmp_path / "n1", tmp_path / "n1" / "n2", tmp_path / "kept" / "n3"]
        raise RuntimeError("the command failed")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept"] and (tmp_path / "kept" / "n3").is_dir()
    (tmp_path / "file").write_text("")
    with pytest.raises(InputError, match="--out-dir .*file: is a file; expected a folder"):
        paths.out_dir(tmp_path / "file", "--out-dir")
    with paths.made_folders() as made:  # a command that succeeds keeps its folders
        paths.out_dir(tmp_path / "n4" / "d")
    assert made == [tmp_path / "n4"] and (tmp_path / "n4").is_dir()
    with paths.made_folders() as made:  # each command lists only its own folders
        paths.out_file(tmp_path / "n5" / "x.png")
    assert made == [tmp_path / "n5"]


def test_in_path_names_the_option(tmp_path):
    assert paths.in_path(tmp_path, "--masks") == tmp_path
    with pytest.raises(InputError, match=r"--target-masks .*nope: not found \(expected a mask video\)"):
        paths.in_path(tmp_path / "nope", "--target-masks", "a mask video")


@pytest.mark.parametrize("parse, good, bad", [
    (argtypes.nonneg_int, {"0": 0, "7": 7}, ["-1", "x", "1.5"]),
    (argtypes.pos_int, {"1": 1}, ["0", "-2"]),
    (argtypes.pos_float, {"0.5": 0.5, "3": 3.0}, ["0", "-1", "inf", "nan", "x"]),
    (argtypes.work_size, {"16": 16, "2048": 2048}, ["0", "24", "2064", "x"]),
    (argtypes.image_size, {"1": 1, "4096": 4096}, ["0", "4097"]),
    (argtypes.exposure_arg, {"auto": "auto", "2": 2.0}, ["0", "-1", "bright"]),
])
def test_argument_types(parse, good, bad):
    for text, value in good.items():
        assert parse(text) == value
    for text in bad:
        with pytest.raises(argparse.ArgumentTypeError, match="expected"):
            parse(text)


def test_key_value_arg_takes_its_keys_late():
    calls = []

    def keys():
        calls.append(1)
        return ("gender", "age")

    parse = argtypes.key_value_arg(keys, float, "NAME")
    assert calls == [] and parse("age=0.5") == ("age", 0.5) and calls == [1]
    with pytest.raises(argparse.ArgumentTypeError, match="NAME=VALUE with NAME in gender, age, got 'size=1'"):
        parse("size=1")
    with pytest.raises(argparse.ArgumentTypeError, match="expected a number after 'age='"):
        parse("age=old")


def test_load_single_light_refuses_a_sequence(tmp_path):
    assert inputs.load_single_light("studio").shape == (9, 3)
    seq = save_light(tmp_path / "seq.npz", torch.zeros(3, 9, 3))
    with pytest.raises(InputError, match=r"expected one light \(K, 3\), got a sequence \(3, 9, 3\)"):
        inputs.load_single_light(str(seq))


def test_shared_options_list_their_choices():
    p = argparse.ArgumentParser()
    options.add_body_args(p)
    options.add_mask_source_arg(p)
    options.add_model_args(p)
    q = argparse.ArgumentParser()
    options.add_model_args(q, backend=False, device=False)  # --checkpoint alone
    assert vars(q.parse_args(["--checkpoint", "m.pt"])) == {"checkpoint": "m.pt"}
    a = p.parse_args(["--pose", "tpose", "--phenotype", "age=0.3", "--mask-source", "head", "--backend", "onnx"])
    assert (a.pose, a.phenotype, a.mask_source, a.backend) == ("tpose", [("age", 0.3)], "head", "onnx")
    with pytest.raises(SystemExit):
        p.parse_args(["--pose", "sitting"])
    text = " ".join(p.format_help().split())
    assert "rest, tpose, apose, arms_down, arms_crossed" in text and "walk, turn, idle, arm_raise" in text
    assert all(name in options.LIGHT_HELP for name in ("city", "studio", "sunset"))


def _unwritable_folder(tmp_path):
    """A folder this user cannot create files in: a 0o555 folder, or (root writes those) /sys or /proc."""
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    for folder in (ro, Path("/sys"), Path("/proc")):
        try:
            (folder / ".probe-test").touch()
        except OSError:
            return folder
        (folder / ".probe-test").unlink()
    raise AssertionError("no folder here refuses a new file")


def test_an_unwritable_output_folder_is_refused_before_work(tmp_path, capsys):
    folder = _unwritable_folder(tmp_path)
    with pytest.raises(InputError, match=r"^OUT .*x.npz: the folder .* is not writable \("):
        paths.out_file(folder / "x.npz", "OUT")
    if folder.is_relative_to(tmp_path):
        with pytest.raises(InputError, match="is not writable"):
            paths.out_dir(folder)
    rc = main(["light", "show", "studio", "--out", str(folder / "x.png")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1 and "the folder" in err[0] and "is not writable" in err[0], err
    assert ".tmp" not in err[0]
    assert not list(tmp_path.rglob(".relightnet-probe-*"))


@pytest.mark.parametrize("argv", [
    ["light", "show", "studio"],
    ["render", "teapot.obj", "--light", "studio"],
    ["render-body", "--light", "studio"],
    ["synth", "--preview", "data"],
])
def test_a_wrong_output_suffix_is_refused_before_work(argv, tmp_path, capsys):
    rc = main([*argv, "--out", str(tmp_path / "x.jpg")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1 and "--out" in err[0] and "expected a file ending in .png" in err[0], err
    assert list(tmp_path.iterdir()) == []
