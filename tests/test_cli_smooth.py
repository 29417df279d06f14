"""`relightnet smooth-light`: round trips, plot, causal methods, one-line errors with nothing written."""

import math

import numpy as np
import pytest
import torch

from relightnet.cli import main
from relightnet.io import read_image
from relightnet.light import load_light, preset_light
from relightnet.sh import rotate_sh_up, save_light
from relightnet.temporal import light_error


@pytest.fixture(scope="module")
def sequences(tmp_path_factory):
    d = tmp_path_factory.mktemp("seq")
    a, b = preset_light("studio"), preset_light("sunset")
    truth = torch.stack([rotate_sh_up(a if t < 50 else b, 0.5 * math.sin(t / 15)) for t in range(90)])
    g = torch.Generator().manual_seed(0)
    noisy = truth + 0.05 * torch.randn(truth.shape, generator=g)
    noisy[[12, 33, 70]] += 2.5
    return save_light(d / "noisy.npz", noisy), save_light(d / "truth.npz", truth), noisy, truth


def test_hermite_round_trip_with_truth_and_plot(tmp_path, sequences, capsys):
    noisy_f, truth_f, noisy, truth = sequences
    out, plot = tmp_path / "out" / "smooth.npz", tmp_path / "plot.png"
    argv = ["smooth-light", str(noisy_f), str(out), "--smoothing", "hermite", "--knots", "8",
            "--outlier-eps", "3mad", "--truth", str(truth_f), "--plot", str(plot)]
    assert main(argv) == 0
    log = capsys.readouterr().err
    sm = load_light(out)
    assert sm.shape == noisy.shape
    assert light_error(sm, truth) < 0.3 * light_error(noisy, truth)
    img = read_image(plot)
    assert img.shape[0] > 300 and img.shape[1] > 500
    assert "outlier(s), switches at frames [50]" in log and "error to truth" in log


@pytest.mark.parametrize("method,extra", [
    ("poly", []), ("savgol", ["--window", "11"]), ("ema", ["--alpha", "0.4"]),
    ("one-euro", ["--min-cutoff", "0.5", "--beta", "1"]), ("fir", ["--window", "4", "--outlier-eps", "none"]),
])
def test_other_methods(tmp_path, sequences, method, extra):
    noisy_f, _, noisy, truth = sequences
    out = tmp_path / "s.json"
    assert main(["-q", "smooth-light", str(noisy_f), str(out), "--smoothing", method, *extra]) == 0
    sm = load_light(out)
    assert sm.shape == noisy.shape and bool(torch.isfinite(sm).all())
    if method != "fir":  # fir here runs without the outlier gate: the spikes pass through, attenuated
        assert light_error(sm, truth) < 0.7 * light_error(noisy, truth)


def test_a_smoothed_file_is_smoothed_again_from_its_raw_estimates(tmp_path, sequences):
    """avatar's OUT.lights.npz and this command's .npz output hold sh (smoothed) and raw: the same format."""
    from relightnet.sh import load_light_sequence, save_light_sequence

    noisy_f, _, noisy, truth = sequences
    lights = save_light_sequence(tmp_path / "clip.lights.npz", truth, raw=noisy, smoothed=truth.numpy(),
                                 outliers=np.zeros(len(noisy), bool), smoothing="pooled")  # as avatar writes it
    assert main(["-q", "smooth-light", str(lights), str(tmp_path / "a.npz"), "--smoothing", "poly"]) == 0
    assert main(["-q", "smooth-light", str(noisy_f), str(tmp_path / "b.npz"), "--smoothing", "poly"]) == 0
    a, side = load_light_sequence(tmp_path / "a.npz")
    assert torch.equal(a, load_light(tmp_path / "b.npz"))  # the raw estimates were smoothed, not the sh
    assert torch.equal(torch.from_numpy(side["raw"]), noisy) and str(side["smoothing"]) == "poly"
    assert side["outliers"].shape == side["switches"].shape == (len(noisy),) and side["outliers"].any()
    # smoothing the output again with another method starts from the same raw estimates
    assert main(["-q", "smooth-light", str(tmp_path / "a.npz"), str(tmp_path / "c.npz"), "--smoothing", "savgol"]) == 0
    assert main(["-q", "smooth-light", str(noisy_f), str(tmp_path / "d.npz"), "--smoothing", "savgol"]) == 0
    assert torch.equal(load_light(tmp_path / "c.npz"), load_light(tmp_path / "d.npz"))


def test_higher_order_sequence_with_a_causal_gate(tmp_path):
    seq = torch.stack([rotate_sh_up(preset_light("forest", lmax=3), 0.02 * t) for t in range(40)])
    seq[17] *= 3.0
    src = save_light(tmp_path / "o3.npz", seq)
    out = tmp_path / "o3_smooth.npz"
    assert main(["-q", "smooth-light", str(src), str(out), "--smoothing", "one-euro", "--outlier-eps", "3mad"]) == 0
    sm = load_light(out)
    assert sm.shape == (40, 16, 3)
    assert (sm[17] - seq[16]).abs().max() < 0.1 * seq[16].abs().max()  # the spike was dropped


def _one_line_error(capsys, rc):
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1, err
    return err[0]


def test_bad_inputs_exit_1_with_one_line_and_nothing_written(tmp_path, sequences, capsys):
    noisy_f, truth_f, noisy, _ = sequences
    out, plot = tmp_path / "o.npz", tmp_path / "p.png"
    tail = [str(out), "--plot", str(plot)]
    one = save_light(tmp_path / "one.npz", preset_light("night"))
    line = _one_line_error(capsys, main(["smooth-light", str(one), *tail]))
    assert "one.npz" in line and "sequence" in line
    k4 = save_light(tmp_path / "k4.npz", noisy[:, :4])
    line = _one_line_error(capsys, main(["smooth-light", str(noisy_f), *tail, "--truth", str(k4)]))
    assert "k4.npz" in line and "ShapeError" in line
    bad_k = tmp_path / "k5.npz"
    np.savez(bad_k, sh=np.zeros((10, 5, 3), np.float32))
    assert "ShapeError" in _one_line_error(capsys, main(["smooth-light", str(bad_k), *tail]))
    nan = tmp_path / "nan.npz"
    arr = noisy.numpy().copy()
    arr[4, 0, 0] = np.nan
    np.savez(nan, sh=arr)
    assert "NaN" in _one_line_error(capsys, main(["smooth-light", str(nan), *tail]))
    with pytest.raises(SystemExit) as e:  # not a method of the table: refused by the parser, listing them
        main(["smooth-light", str(noisy_f), *tail, "--smoothing", "kalman"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "kalman" in err and "hermite" in err
    line = _one_line_error(capsys, main(["smooth-light", str(noisy_f), *tail, "--outlier-eps", "3sigma"]))
    assert "3sigma" in line
    line = _one_line_error(capsys, main(["smooth-light", str(noisy_f), *tail, "--smoothing", "ema",
                                         "--outlier-eps", "0.5"]))
    assert "causal" in line
    # an option of another method would be ignored: refused, naming the methods it belongs to
    line = _one_line_error(capsys, main(["smooth-light", str(noisy_f), *tail, "--smoothing", "ema", "--knots", "4"]))
    assert "--knots: applies to --smoothing hermite, not ema" in line
    line = _one_line_error(capsys, main(["smooth-light", str(noisy_f), *tail, "--alpha", "0.5"]))
    assert "--alpha: applies to --smoothing ema, not hermite" in line
    assert "o.npy" in _one_line_error(capsys, main(["smooth-light", str(noisy_f), str(tmp_path / "o.npy")]))
    line = _one_line_error(capsys, main(["smooth-light", str(noisy_f), str(out), "--plot", str(tmp_path / "p.jpg")]))
    assert "png" in line
    assert "missing" in _one_line_error(capsys, main(["smooth-light", str(tmp_path / "missing.npz"), *tail]))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["k4.npz", "k5.npz", "nan.npz", "one.npz"]
