"""A user's light (:func:`relightnet.light.load_light`): words, preset names and files, each where it belongs."""

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.light import light_from_words, load_light, preset_light, preset_names
from relightnet.sh import load_light_file, save_light


def test_preset_names_load():
    sh = load_light("studio")
    assert sh.shape == (9, 3) and (sh[0] > 0).all()
    assert load_light("night", lmax=1).shape == (4, 3)
    torch.testing.assert_close(load_light("sunset", lmax=3), preset_light("sunset", 3))


def test_words_load_at_the_order_asked():
    torch.testing.assert_close(load_light("key:az=30 + ambient:0.2"), light_from_words("key:az=30 + ambient:0.2"))
    assert load_light("key:az=30", lmax=3).shape == (16, 3)


def test_files_and_arrays_load_as_the_file_reader_reads_them(tmp_path):
    sh = torch.randn(9, 3, generator=torch.Generator().manual_seed(0))
    path = save_light(tmp_path / "l.npz", sh)
    torch.testing.assert_close(load_light(path), load_light_file(path))
    torch.testing.assert_close(load_light(str(path), lmax=1), load_light_file(path, lmax=1))
    torch.testing.assert_close(load_light(sh.numpy()), sh)


def test_a_preset_wins_over_a_same_named_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    np.savez(tmp_path / "studio", sh=np.zeros((9, 3), np.float32))  # studio.npz, not "studio"
    (tmp_path / "studio").write_bytes((tmp_path / "studio.npz").read_bytes())
    torch.testing.assert_close(load_light("studio"), preset_light("studio"))


def test_unknown_preset_lists_the_presets_and_other_inputs_are_refused(tmp_path):
    with pytest.raises(InputError, match="sunnyday") as e:
        load_light("sunnyday")
    for name in preset_names():
        assert name in str(e.value)
    with pytest.raises(InputError, match="missing.npz"):
        load_light(tmp_path / "missing.npz")
    with pytest.raises(InputError, match="expected a path, preset name or array"):
        load_light(3)
    with pytest.raises(InputError, match="expected a path, preset name or array"):
        load_light_file(3)
