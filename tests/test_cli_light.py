"""`relightnet light show|convert`, in-process and as a subprocess (the demo: tests/pipeline)."""

import os
import subprocess
import sys

import numpy as np
import pytest
import torch

from relightnet.cli import main
from relightnet.io import read_image
from relightnet.light import load_light, preset_light
from relightnet.sh import save_light


def test_show_preset_writes_png(tmp_path):
    out = tmp_path / "studio.png"
    assert main(["light", "show", "studio", "--out", str(out), "--size", "48"]) == 0
    img = read_image(out)
    assert img.shape == (48, 48 * 6 + 12, 3)  # front, back, SH lat-long, original map
    assert img[:, :48].max() > 0.5


def test_show_light_file_and_fixed_exposure(tmp_path):
    light = save_light(tmp_path / "l.npz", preset_light("night"))
    out = tmp_path / "sub" / "night.png"  # missing output folders are created
    assert main(["light", "show", str(light), "--out", str(out), "--size", "32", "--exposure", "0.5"]) == 0
    assert read_image(out).shape == (32, 32 * 4 + 8, 3)  # no original map for a coefficient file


def test_convert_ke18_and_npz_both_ways(tmp_path):
    sh = preset_light("sunrise")
    ke = tmp_path / "ke.npy"
    assert main(["light", "convert", "sunrise", str(ke)]) == 0
    np.testing.assert_array_equal(np.load(ke), sh.numpy()[:, ::-1])  # BGR columns on disk
    npz = tmp_path / "ours.npz"
    assert main(["light", "convert", str(ke), str(npz)]) == 0
    torch.testing.assert_close(load_light(npz), sh, rtol=0, atol=0)
    back = tmp_path / "back.npy"
    assert main(["light", "convert", str(npz), str(back)]) == 0
    np.testing.assert_array_equal(np.load(back), np.load(ke))
    js = tmp_path / "o3.json"
    assert main(["-q", "light", "convert", "sunrise", str(js), "--lmax", "3"]) == 0
    assert load_light(js).shape == (16, 3)


def _one_line_error(capsys, rc):
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1
    return err[0]


def test_bad_inputs_exit_1_with_one_line_and_no_output(tmp_path, capsys):
    out = tmp_path / "x.png"
    line = _one_line_error(capsys, main(["light", "show", str(tmp_path / "missing.npz"), "--out", str(out)]))
    assert "missing.npz" in line and "InputError" in line
    bad = tmp_path / "bad.npy"
    np.save(bad, np.zeros((4, 3)))
    line = _one_line_error(capsys, main(["light", "convert", str(bad), str(tmp_path / "o.npz")]))
    assert "bad.npy" in line and "ShapeError" in line
    big = save_light(tmp_path / "big.npz", torch.ones(16, 3))
    line = _one_line_error(capsys, main(["light", "convert", str(big), str(tmp_path / "o.npy")]))
    assert "Kanamori" in line
    line = _one_line_error(capsys, main(["light", "show", "sunnyday", "--out", str(out)]))
    assert "studio" in line
    line = _one_line_error(capsys, main(["light", "convert", "studio", str(tmp_path / "o.txt")]))
    assert "o.txt" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.npy", "big.npz"]


def test_bad_arguments_are_usage_errors(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["light", "show", "studio", "--exposure", "-2"])
    assert e.value.code == 2
    assert main(["light"]) == 2  # no subcommand: help


@pytest.mark.slow
def test_subprocess(tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    out = tmp_path / "sunset.png"
    ok = subprocess.run(
        [sys.executable, "-m", "relightnet.cli", "light", "show", "sunset", "--out", str(out), "--size", "32"],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert ok.returncode == 0, ok.stderr
    assert "wrote" in ok.stderr and read_image(out).shape[0] == 32
    bad = subprocess.run(
        [sys.executable, "-m", "relightnet.cli", "light", "convert", str(tmp_path / "nope.json"),
         str(tmp_path / "o.npz")],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert bad.returncode == 1
    assert len(bad.stderr.strip().splitlines()) == 1 and "nope.json" in bad.stderr
    assert not (tmp_path / "o.npz").exists()
