"""relightnet.data.config: the generator's settings — defaults, files, validation, per-sample seeds."""

import json

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.data.config import HDRI_NAMES, SPLITS, SynthConfig, load_config, sample_seed
from relightnet.names import light_presets


def test_defaults_round_trip_through_a_file(tmp_path):
    cfg = SynthConfig()
    assert cfg.res % 16 == 0 and cfg.n_coeffs == (cfg.lmax + 1) ** 2 and set(cfg.counts) <= set(SPLITS)
    (tmp_path / "c.json").write_text(json.dumps(cfg.to_dict()))
    assert load_config(tmp_path / "c.json") == cfg
    (tmp_path / "c.yaml").write_text("res: 64\nseed: 3\ncounts: {train: 5, val: 0, test: 2}\n")
    c = load_config(tmp_path / "c.yaml")
    assert (c.res, c.seed, c.counts) == (64, 3, {"train": 5, "val": 0, "test": 2})
    assert c.replace(res=32).res == 32 and c.res == 64


def test_test_maps_are_held_out_and_shipped():
    cfg = SynthConfig()
    assert set(HDRI_NAMES) == set(light_presets())  # every name is a shipped map
    assert set(cfg.hdris("test")).isdisjoint(cfg.hdris("train")) and cfg.hdris("val") == cfg.hdris("train")


@pytest.mark.parametrize("change, message", [
    ({"res": 100}, "config res: expected a multiple of 16 from 16 to 4096, got 100"),
    ({"lmax": 9}, r"config lmax: expected an integer in \[0, 8\]"),
    ({"seed": -1}, "config seed: expected an integer >= 0"),
    ({"n_dirs": 4}, "config n_dirs: expected an integer from 8"),
    ({"counts": {"train": -1}}, "config counts"),
    ({"hdri_train": ("moon",)}, "config hdri_train: expected a non-empty list"),
    ({"sequence_frames": 20000}, "config sequence_frames"),
    ({"clip_lights": "strobe"}, "config clip_lights: expected 'random', 'constant' or 'switch'"),
])
def test_bad_values_name_the_key(change, message):
    with pytest.raises(InputError, match=message):
        SynthConfig().replace(**change)


def test_bad_files(tmp_path):
    with pytest.raises(InputError, match="missing.yaml: config file not found"):
        load_config(tmp_path / "missing.yaml")
    (tmp_path / "list.yaml").write_text("- 1\n- 2\n")
    with pytest.raises(InputError, match="expected a mapping of config keys"):
        load_config(tmp_path / "list.yaml")
    (tmp_path / "typo.json").write_text('{"resolution": 64}')
    with pytest.raises(InputError, match=r"unknown keys \['resolution'\]"):
        load_config(tmp_path / "typo.json")
    (tmp_path / "bad.yaml").write_text("res: [unclosed\n")
    with pytest.raises(InputError, match="bad.yaml: unreadable config"):
        load_config(tmp_path / "bad.yaml")


def test_sample_seeds_depend_on_seed_split_and_index_only():
    cfg = SynthConfig(seed=7)
    draw = lambda s, i: np.random.default_rng(sample_seed(cfg, s, i)).random()  # noqa: E731
    assert draw("train", 3) == draw("train", 3)
    assert len({draw("train", 3), draw("test", 3), draw("train", 4)}) == 3
    assert np.random.default_rng(sample_seed(cfg.replace(seed=8), "train", 3)).random() != draw("train", 3)
    with pytest.raises(InputError, match="split: expected one of"):
        sample_seed(cfg, "dev", 0)
    with pytest.raises(InputError, match="index: expected >= 0"):
        sample_seed(cfg, "train", -1)
