"""Light files (:func:`relightnet.sh.load_light_file`): formats, round trips, KE18 BGR columns, env-map projection,
errors naming the file."""

import json

import numpy as np
import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.io import write_envmap
from relightnet.sh import load_light_file, project_envmap, resize_sh, save_light, sh_to_envmap


def _light(*shape, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.randn(*shape, generator=g)


def test_ke18_npy_is_bgr_and_round_trips(tmp_path):
    sh = _light(9, 3)
    path = save_light(tmp_path / "ke.npy", sh)
    raw = np.load(path)
    assert raw.shape == (9, 3)
    np.testing.assert_array_equal(raw[:, 0], sh[:, 2].numpy())  # column 0 is blue
    np.testing.assert_array_equal(raw[:, 2], sh[:, 0].numpy())
    back = load_light_file(path)
    assert back.dtype == torch.float32
    torch.testing.assert_close(back, sh, rtol=0, atol=0)


def test_ke18_file_written_elsewhere_loads_as_rgb(tmp_path):
    bgr = np.zeros((9, 3), np.float64)
    bgr[0] = [0.1, 0.2, 0.9]  # B, G, R: a red light
    np.save(tmp_path / "red.npy", bgr)
    sh = load_light_file(tmp_path / "red.npy")
    torch.testing.assert_close(sh[0], torch.tensor([0.9, 0.2, 0.1]))


@pytest.mark.parametrize("suffix", [".npz", ".json"])
@pytest.mark.parametrize("shape", [(9, 3), (16, 3), (1, 3), (5, 9, 3), (2, 25, 3)])
def test_ours_round_trip(tmp_path, suffix, shape):
    sh = _light(*shape, seed=len(shape))
    path = save_light(tmp_path / f"l{suffix}", sh)
    back = load_light_file(path)
    assert back.shape == shape and back.dtype == torch.float32
    torch.testing.assert_close(back, sh, rtol=0, atol=0)


def test_npz_and_json_metadata(tmp_path):
    sh = _light(4, 16, 3)
    with np.load(save_light(tmp_path / "l.npz", sh)) as z:
        assert z["sh"].dtype == np.float32 and z["sh"].shape == (4, 16, 3)
        assert int(z["lmax"]) == 3 and str(z["frame"]) == "light" and str(z["units"]) == "linear radiance"
    doc = json.loads(save_light(tmp_path / "l.json", sh[0]).read_text())
    assert doc["lmax"] == 3 and doc["frame"] == "light" and doc["units"] == "linear radiance"
    assert np.asarray(doc["sh"]).shape == (16, 3)


def test_lmax_truncates_or_pads_stored_lights(tmp_path):
    sh = _light(16, 3)
    path = save_light(tmp_path / "l.npz", sh)
    torch.testing.assert_close(load_light_file(path, lmax=1), sh[:4])
    padded = load_light_file(path, lmax=4)
    assert padded.shape == (25, 3)
    torch.testing.assert_close(padded[:16], sh)
    assert (padded[16:] == 0).all()
    torch.testing.assert_close(resize_sh(_light(3, 9, 3), 1), _light(3, 9, 3)[:, :4])


def test_arrays_pass_through_validated():
    sh = _light(9, 3)
    out = load_light_file(sh.double().numpy())
    torch.testing.assert_close(out, sh)
    with pytest.raises(ShapeError):
        load_light_file(torch.zeros(8, 3))
    with pytest.raises(InputError, match="NaN"):
        load_light_file(torch.full((9, 3), float("inf")))


def _positive_light(seed=0):
    sh = _light(9, 3, seed=seed) * 0.3
    sh[0] = torch.tensor([3.0, 2.5, 2.0])
    return sh


def test_envmap_projection_recovers_known_coefficients(tmp_path):
    sh = _positive_light()
    env = sh_to_envmap(sh, 64)
    assert env.min() > 0  # nothing for the loader's clamp to change
    torch.testing.assert_close(project_envmap(env, 2), sh, rtol=0, atol=2e-3)
    exr = write_envmap(tmp_path / "syn.exr", env)
    torch.testing.assert_close(load_light_file(exr), sh, rtol=0, atol=2e-3)
    hdr = write_envmap(tmp_path / "syn.hdr", env)
    torch.testing.assert_close(load_light_file(hdr), sh, rtol=0, atol=3e-2)
    # A higher-order projection keeps the order-2 part and finds (almost) nothing above it.
    sh4 = load_light_file(exr, lmax=4)
    assert sh4.shape == (25, 3)
    torch.testing.assert_close(sh4[:9], sh, rtol=0, atol=2e-3)
    assert sh4[9:].abs().max() < 5e-3


# --- bad inputs: the right error type, the file in the message -------------------------------


def test_wrong_npy_shape(tmp_path):
    p = tmp_path / "bad_shape.npy"
    np.save(p, np.zeros((4, 3)))
    with pytest.raises(ShapeError, match="bad_shape.npy"):
        load_light_file(p)
    np.save(p, np.zeros((9, 3, 1)))
    with pytest.raises(ShapeError, match="bad_shape.npy"):
        load_light_file(p)


@pytest.mark.parametrize("suffix", [".npz", ".json", ".npy"])
def test_nan_coefficients(tmp_path, suffix):
    bad = np.zeros((9, 3), np.float32)
    bad[3, 1] = np.nan
    p = tmp_path / f"nan_light{suffix}"
    if suffix == ".npz":
        np.savez(p, sh=bad, lmax=2)
    elif suffix == ".npy":
        np.save(p, bad)
    else:
        p.write_text('{"sh": ' + json.dumps(bad.tolist()) + "}")
    with pytest.raises(InputError, match=f"nan_light\\{suffix}.*NaN"):
        load_light_file(p)


def test_wrong_coefficient_count(tmp_path):
    p = tmp_path / "k10.npz"
    np.savez(p, sh=np.zeros((10, 3), np.float32))
    with pytest.raises(ShapeError, match="k10.npz"):
        load_light_file(p)
    np.savez(p, sh=np.zeros((9, 4), np.float32))
    with pytest.raises(ShapeError, match="k10.npz"):
        load_light_file(p)
    np.savez(p, sh=np.zeros((9, 3), np.float32), lmax=3)
    with pytest.raises(ShapeError, match="k10.npz.*lmax"):
        load_light_file(p)
    p2 = tmp_path / "k.json"
    p2.write_text('{"sh": [[1, 2, 3], [4, 5]]}')
    with pytest.raises(ShapeError, match="k.json"):
        load_light_file(p2)


@pytest.mark.parametrize("suffix", [".npz", ".json", ".npy", ".exr", ".hdr"])
def test_garbage_files(tmp_path, suffix):
    p = tmp_path / f"garbage{suffix}"
    p.write_bytes(b"\x00\x01not a light at all\xff" * 20)
    with pytest.raises(InputError, match=f"garbage\\{suffix}"):
        load_light_file(p)


def test_missing_file_and_other_inputs(tmp_path):
    with pytest.raises(InputError, match="missing.npz"):
        load_light_file(tmp_path / "missing.npz")
    with pytest.raises(InputError, match="missing.json"):
        load_light_file(str(tmp_path / "missing.json"))
    p = tmp_path / "light.txt"
    p.write_text("1 2 3")
    with pytest.raises(InputError, match="light.txt.*unsupported"):
        load_light_file(p)
    p = tmp_path / "other.npz"
    np.savez(p, coeffs=np.zeros((9, 3)))
    with pytest.raises(InputError, match="other.npz.*'sh'"):
        load_light_file(p)
    np.savez(p, sh=np.zeros((9, 3)), frame="world")
    with pytest.raises(InputError, match="other.npz.*frame"):
        load_light_file(p)


def test_save_errors_leave_nothing(tmp_path):
    with pytest.raises(ShapeError, match="Kanamori"):
        save_light(tmp_path / "x.npy", _light(16, 3))
    with pytest.raises(ShapeError, match="Kanamori"):
        save_light(tmp_path / "x.npy", _light(2, 9, 3))
    with pytest.raises(InputError, match="NaN"):
        save_light(tmp_path / "x.npz", torch.full((9, 3), float("nan")))
    with pytest.raises(InputError, match="x.txt"):
        save_light(tmp_path / "x.txt", _light(9, 3))
    with pytest.raises(ShapeError):
        save_light(tmp_path / "x.npz", _light(9, 2))
    assert list(tmp_path.iterdir()) == []


def test_light_sequence_round_trip_with_side_arrays(tmp_path):
    from relightnet.sh import load_light_sequence, save_light_sequence

    g = torch.Generator().manual_seed(3)
    sh, raw = torch.randn(5, 9, 3, generator=g), torch.randn(5, 9, 3, generator=g)
    flags = torch.tensor([False, True, False, False, True])
    path = save_light_sequence(tmp_path / "seq.npz", sh, raw=raw, outliers=flags, smoothing="hermite",
                               evidence_M=np.zeros((5, 3, 9, 9), np.float32))
    assert torch.equal(load_light_file(path), sh)  # every light reader sees the sequence
    got, side = load_light_sequence(path)
    assert torch.equal(got, sh) and set(side) == {"raw", "outliers", "smoothing", "evidence_M"}
    assert np.array_equal(side["raw"], raw.numpy()) and side["outliers"].tolist() == flags.tolist()
    assert str(side["smoothing"]) == "hermite" and side["evidence_M"].shape == (5, 3, 9, 9)
    _, only = load_light_sequence(path, ("raw", "absent"))
    assert set(only) == {"raw"}
    save_light(tmp_path / "plain.json", sh)  # a sequence without side arrays, in any of our formats
    got, side = load_light_sequence(tmp_path / "plain.json")
    assert torch.allclose(got, sh) and side == {}
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_light_sequence_errors_name_the_file(tmp_path):
    from relightnet.sh import load_light_sequence, save_light_sequence

    sh = torch.zeros(4, 9, 3)
    with pytest.raises(ShapeError, match=r"seq.npz: side array 'raw' has 3 rows; expected one per frame \(4\)"):
        save_light_sequence(tmp_path / "seq.npz", sh, raw=torch.zeros(3, 9, 3))
    with pytest.raises(InputError, match="names \\['lmax'\\] are the light's own"):
        save_light_sequence(tmp_path / "seq.npz", sh, lmax=2)
    with pytest.raises(InputError, match="written as .npz"):
        save_light_sequence(tmp_path / "seq.json", sh)
    with pytest.raises(ShapeError, match=r"expected a light sequence \(T, K, 3\)"):
        save_light_sequence(tmp_path / "seq.npz", sh[0])
    with pytest.raises(InputError, match="dtype object"):
        save_light_sequence(tmp_path / "seq.npz", sh, notes=np.array([{"a": 1}] * 4, dtype=object))
    assert list(tmp_path.iterdir()) == []
    save_light(tmp_path / "one.npz", sh[0])
    with pytest.raises(ShapeError, match=r"one.npz: expected a light sequence \(T, K, 3\), got one light"):
        load_light_sequence(tmp_path / "one.npz")
    np.savez(tmp_path / "bad.npz", sh=np.zeros((4, 9, 3), np.float32), raw=np.zeros((2, 9, 3), np.float32))
    with pytest.raises(ShapeError, match="bad.npz: side array 'raw' has 2 rows"):
        load_light_sequence(tmp_path / "bad.npz")


def test_lights_no_scene_has_are_refused_and_ringing_is_not(caplog):
    from relightnet.light import load_light
    from relightnet.sh.io import MAX_IRRADIANCE, check_light_physics

    huge = torch.zeros(9, 3)
    huge[0] = 1e30
    split = huge.clone()
    split[1] = -1e30  # half the sphere +1e30, half -1e30: "half red, half cyan"
    for light, words in ((huge, r"reaches 8.86e\+29"), (split, "reaches"), (-torch.ones(9, 3), "R irradiance is "
                                                                                                  "negative over")):
        with pytest.raises(InputError, match=rf"light x.npy: its .*{words}") as e:
            check_light_physics(light, "x.npy")
        assert "\n" not in str(e.value)
    seq = torch.stack([load_light("studio"), -torch.ones(9, 3)])
    with pytest.raises(InputError, match=r"light seq \(frame 1\): its R irradiance is negative"):
        check_light_physics(seq, "seq")
    # A single directional source rings below zero behind it at order 2: accepted without a word.
    with caplog.at_level("WARNING", logger="relightnet.sh.io"):
        for name in ("key:az=30,el=10,power=3", "studio", "sunset", "sunrise", "night"):
            check_light_physics(load_light(name), name)
    assert caplog.text == ""
    # Mild negatives (a third of the sphere, green only) pass with a warning naming the channel.
    mild = torch.zeros(9, 3)
    mild[0], mild[1:4, 1] = 0.5, -1.2
    with caplog.at_level("WARNING", logger="relightnet.sh.io"):
        check_light_physics(mild, "mild")
    assert "light mild: its G irradiance is negative over" in caplog.text
    # The bound is on irradiance: a bright physical HDR light below it passes.
    bright = torch.zeros(9, 3)
    bright[0] = MAX_IRRADIANCE / 10
    assert check_light_physics(bright, "bright") is bright
