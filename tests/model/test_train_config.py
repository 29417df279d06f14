"""The training configuration: typed sections, Literal modes, every shipped YAML, older checkpoints' configs."""

import typing
from pathlib import Path

import pytest
import torch

from relightnet.checks import InputError
from relightnet.data.augment import Augment
from relightnet.model.losses import LossWeights
from relightnet.model.network import NetConfig
from relightnet.model.photo_input import PhotoInput
from relightnet.model.round_trip import NOVEL_LIGHTS
from relightnet.model.train_config import AugmentConfig, NovelLight, TrainConfig, load_train_config

REPO = Path(__file__).resolve().parents[2]


def _plain(v):
    return [_plain(x) for x in v] if isinstance(v, (list, tuple)) else v


def test_sections_are_typed_and_round_trip_through_plain_values():
    cfg = TrainConfig(net={"width": 8, "light_mode": "solve"}, loss={"tv": 0.1},
                      augment={"flip": 0.0, "crop_scale": [0.5, 0.5]}, photo={"composite": 1.0})
    assert isinstance(cfg.net, NetConfig) and cfg.net == NetConfig(width=8, light_mode="solve")
    assert isinstance(cfg.loss, LossWeights) and cfg.loss == LossWeights(tv=0.1)
    assert cfg.augment == AugmentConfig(flip=0.0, crop_scale=(0.5, 0.5))
    assert cfg.photo == PhotoInput(composite=1.0)
    d = cfg.to_dict()
    assert d["net"]["width"] == 8 and d["augment"]["crop_scale"] == [0.5, 0.5] and d["photo"]["pad"] == [0.03, 0.08]
    assert TrainConfig.from_dict(d) == cfg and TrainConfig(**d) == cfg
    # empty sections: no augmentation, no photo framing (as before)
    assert TrainConfig(augment={}, photo={}).augment is None and TrainConfig(photo={}).photo is None
    assert TrainConfig().augment == AugmentConfig(crop_scale=(0.875, 0.875))


def test_the_augment_section_builds_the_same_augment_as_its_mapping():
    raw = {"flip": 0.5, "crop_scale": [0.875, 0.875], "intensity": [0.5, 2.0], "white_balance": 0.1}
    a = Augment(**{**raw, "crop_scale": tuple(raw["crop_scale"])})
    b = Augment(**vars(TrainConfig(augment=raw).augment))
    item = {"image": torch.rand(3, 32, 32), "mask": torch.ones(1, 32, 32)}
    out_a, out_b = a(dict(item), torch.Generator().manual_seed(3)), b(dict(item), torch.Generator().manual_seed(3))
    assert out_a.keys() == out_b.keys() and all(torch.equal(out_a[k], out_b[k]) for k in out_a)


@pytest.mark.parametrize("kwargs, message", [
    ({"precision": "fp8"}, "train config precision: expected one of 'fp32', 'bf16', got 'fp8'"),
    ({"target": "normals"}, "train config target: expected one of 'transport', 'transport_unoccluded', got 'normals'"),
    ({"render_target": 3}, "train config render_target: expected one of 'image', 'model', got 3"),
    ({"data_dtype": "int8"}, "train config data_dtype: expected one of 'float32', 'float16', got 'int8'"),
    ({"novel_light": "sun"}, "train config novel_light: expected one of 'batch', 'side', got 'sun'"),
    ({"augment": {"mode": "cubic"}}, "train config augment mode: expected one of 'nearest', 'bilinear', got 'cubic'"),
    ({"net": {"light_mode": "guess"}}, "net config light_mode: expected one of"),
    ({"net": {"depth": 3}}, "train config net: unknown keys"),
    ({"loss": {"bogus": 1.0}}, "train config loss: unknown keys"),
    ({"augment": {"crop_scale": [0.5, 1.0]}}, "train config augment.crop_scale: a range"),
    ({"net": "wide"}, "train config net: expected a mapping, got str"),
    ({"augment": {"crop_scale": {"lo": 0.5, "hi": 0.5}}}, "train config augment.crop_scale: expected [lo, hi]"),
    ({"photo": "yes"}, "train config photo: expected a mapping, got str"),
])
def test_a_bad_mode_is_one_line_naming_the_field_and_the_choices(kwargs, message):
    with pytest.raises(InputError) as e:
        TrainConfig(**kwargs)
    assert str(e.value).startswith(message) and "\n" not in str(e.value)


def test_the_novel_light_choices_are_the_round_trips():
    assert typing.get_args(NovelLight) == NOVEL_LIGHTS


def test_every_config_in_train_configs_loads_with_its_values():
    import yaml

    from relightnet.data import load_config

    configs = sorted((REPO / "train" / "configs").glob("*.yaml"))
    synth = [p for p in configs if p.name.startswith(("data_", "seq_"))]  # the datasets: relightnet synth configs
    train_ = [p for p in configs if p not in synth]
    assert len(train_) >= 10 and {"tiny.yaml", "small.yaml", "clothed_photo_side.yaml"} <= {p.name for p in train_}
    for path in train_:
        raw, cfg = yaml.safe_load(path.read_text()), load_train_config(path)
        for key, value in raw.items():
            if isinstance(value, (int, float, str)):
                assert getattr(cfg, key) == value, (path.name, key)
            elif isinstance(value, dict):  # a section: each of its values, typed
                section = getattr(cfg, key)
                if key in ("augment", "photo"):  # an empty one: none
                    assert (section is None) == (not value), (path.name, key)
                for k, v in value.items():
                    assert _plain(getattr(section, k)) == v, (path.name, key, k)
    for path in synth:
        raw, cfg = yaml.safe_load(path.read_text()), load_config(path)
        assert cfg.res == raw.get("res", cfg.res) and cfg.seed == raw.get("seed", cfg.seed), path.name


@pytest.mark.parametrize("path", sorted([*(REPO / "train" / "checkpoints").glob("*.pt"),
                                         *(REPO / "relightnet" / "weights").glob("*.pt")]), ids=lambda p: p.name)
def test_the_training_config_of_every_shipped_checkpoint_loads_with_its_values(path):
    state = torch.load(path, map_location="cpu", weights_only=True)
    stored = state["train_config"]
    d = TrainConfig.from_dict(stored, str(path)).to_dict()
    for key, value in stored.items():
        if isinstance(value, dict):
            assert {k: d[key][k] for k in value} == value, key  # partial sections: the rest are defaults
        else:
            assert d[key] == value, key
