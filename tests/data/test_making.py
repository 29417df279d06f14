"""Making shards in this process: make_items / make_shard / make_and_write_shard and the manifest's fields."""

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.data.config import SynthConfig
from relightnet.data.generate import generate_sample, prepare_assets
from relightnet.data.making import fields_of, make_and_write_shard, make_items, make_shard
from relightnet.data.shards import read_shard, shard_name

CFG = SynthConfig(res=16, n_dirs=8, shard_size=2, counts={"train": 3, "val": 0, "test": 0})


@pytest.fixture(scope="module")
def assets(anny_body):
    return prepare_assets(anny_body, texture_size=64)


def test_fields_of_lists_per_item_shapes():
    arrays = {"image": np.zeros((4, 8, 8, 3), np.uint8), "light": np.zeros((4, 9, 3), np.float32),
              "meta": np.array(["{}"] * 4)}
    assert fields_of(arrays) == {"image": {"shape": [8, 8, 3], "dtype": "uint8"},
                                 "light": {"shape": [9, 3], "dtype": "float32"}}


def test_make_items_is_single_threaded_and_matches_the_generator(assets):
    n = torch.get_num_threads()
    items = make_items(CFG, "train", [2], assets)
    assert torch.get_num_threads() == n  # restored
    torch.set_num_threads(1)
    try:
        ref = generate_sample(CFG, "train", 2, assets)
    finally:
        torch.set_num_threads(n)
    assert len(items) == 1 and items[0].meta == ref.meta
    for k, v in ref.arrays.items():
        assert items[0].arrays[k].tobytes() == v.tobytes(), k


def test_make_and_write_shard_writes_what_make_shard_makes(assets, tmp_path):
    ticks = []
    info = make_and_write_shard(CFG, "train", 1, tmp_path, body=assets, tick=lambda: ticks.append(1))
    assert (info["split"], info["index"], info["start"], info["count"]) == ("train", 1, 2, 1) and len(ticks) == 1
    path = tmp_path / shard_name("train", 1)
    assert path.is_file() and info["bytes"] == path.stat().st_size and len(info["sha256"]) == 64
    written = read_shard(path)
    made = make_shard(CFG, "train", 1, assets)
    assert info["fields"] == fields_of(made)
    assert written["meta"][0]["seed"] == {"seed": CFG.seed, "split": "train", "index": 2}
    for k, v in made.items():
        if k != "meta":
            assert v.shape[0] == 1 and np.array_equal(written[k], v), k
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # nothing else left
    with pytest.raises(InputError, match="shard index: train has 2 shards, got 2"):
        make_shard(CFG, "train", 2, assets)
