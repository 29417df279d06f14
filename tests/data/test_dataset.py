import json
import shutil

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.data import SynthConfig
from relightnet.data.augment import Augment
from relightnet.data.dataset import SynthDataset, to_cnn_layout
from relightnet.data.synth import run_synth

ALL = ("image", "mask", "albedo", "transport", "transport_unoccluded", "light", "normals", "depth", "parts",
       "image_srgb", "background", "image_composite")


@pytest.fixture(scope="module")
def root(tiny_dataset):
    """6 train samples in shards of 4 + 2, 3 test samples, at 32²."""
    return tiny_dataset


def _residual(s):
    """max |image − albedo ⊙ (T·L)| relative to the image's max (clips: every frame)."""
    shading = torch.einsum("...khw,...kc->...chw", s["transport"], s["light"])
    return float((s["image"] - s["albedo"] * shading).abs().max() / s["image"].abs().max())


@pytest.mark.slow
def test_items_layout_and_identity(root):
    ds = SynthDataset(root, fields=ALL)
    assert len(ds) == 6 and len(SynthDataset(root, "val")) == 0 and len(SynthDataset(root, "test")) == 3
    s = ds[5]
    shapes = {k: (tuple(v.shape), v.dtype) for k, v in s.items()}
    f32, u8 = torch.float32, torch.uint8
    assert shapes == {
        "image": ((3, 32, 32), f32), "mask": ((1, 32, 32), f32), "albedo": ((3, 32, 32), f32),
        "transport": ((9, 32, 32), f32), "transport_unoccluded": ((9, 32, 32), f32), "light": ((9, 3), f32),
        "normals": ((3, 32, 32), f32), "depth": ((1, 32, 32), f32), "parts": ((1, 32, 32), u8),
        "image_srgb": ((3, 32, 32), u8), "background": ((3, 32, 32), f32), "image_composite": ((3, 32, 32), u8),
        "index": ((), torch.int64),
    }
    assert int(s["index"]) == 5 and ds.meta(5)["seed"]["index"] == 5
    for i in range(len(ds)):
        assert _residual(ds[i]) < 1e-5
    assert torch.equal(ds[-1]["image"], s["image"])
    with pytest.raises(IndexError):
        ds[6]
    # Items are copies: changing one does not change the cached shard.
    s["image"].zero_()
    assert ds[5]["image"].abs().max() > 0
    assert to_cnn_layout("mask", np.zeros((2, 4, 5)), sequence=True).shape == (2, 1, 4, 5)


def test_lazy_bounded_cache(root):
    ds = SynthDataset(root, cache_shards=1)
    assert not ds._cache
    ds[0], ds[5], ds[1]
    assert list(ds._cache) == [0] and set(ds._cache[0]) == {"image", "mask", "albedo", "transport", "light",
                                                             "normals"}


def test_augmented_items_keep_identity(root):
    aug = Augment(flip=0.5, crop_scale=(0.5, 1.0), intensity=(0.5, 2.0), white_balance=0.2)
    ds = SynthDataset(root, augment=aug, augment_seed=7)
    for i in range(len(ds)):
        s = ds[i]
        h, w = s["image"].shape[-2:]
        assert h % 16 == 0 and w % 16 == 0 and s["transport"].shape[-2:] == (h, w)
        assert _residual(s) < 1e-5
        assert torch.equal(s["image"], ds[i]["image"])  # augment_seed: the same every time
    assert _residual(SynthDataset(root, augment=aug)[0]) < 1e-5


def test_dataloader_workers(root):
    ds = SynthDataset(root, fields=("image", "light", "parts"))
    dl = torch.utils.data.DataLoader(ds, batch_size=4, num_workers=2, shuffle=False)
    batches = list(dl)
    assert [tuple(b["image"].shape) for b in batches] == [(4, 3, 32, 32), (2, 3, 32, 32)]
    assert batches[0]["light"].shape == (4, 9, 3) and batches[1]["index"].tolist() == [4, 5]
    assert torch.equal(batches[1]["image"][1], ds[5]["image"])


def test_bad_datasets(root, tmp_path):
    with pytest.raises(InputError, match="not in this dataset"):
        SynthDataset(root, fields=("image", "shadow"))
    with pytest.raises(InputError, match="split"):
        SynthDataset(root, "training")
    with pytest.raises(InputError, match="no manifest"):
        SynthDataset(tmp_path)
    d = tmp_path / "partial"
    shutil.copytree(root, d)
    m = json.loads((d / "manifest.json").read_text())
    m["splits"]["train"]["shards"] = m["splits"]["train"]["shards"][:1]
    (d / "manifest.json").write_text(json.dumps(m))
    with pytest.raises(InputError, match="1 of 2 shards"):
        SynthDataset(d)
    assert len(SynthDataset(d, allow_incomplete=True)) == 4


def test_clip_dataset(tmp_path, anny_body):
    cfg = SynthConfig(res=32, n_dirs=16, shard_size=1, counts={"train": 1, "val": 0, "test": 0}, sequence_frames=2)
    run_synth(tmp_path / "clips", cfg, workers=0, progress=False, body=anny_body)
    s = SynthDataset(tmp_path / "clips", fields=("image", "mask", "albedo", "transport", "light"))[0]
    assert s["image"].shape == (2, 3, 32, 32) and s["mask"].shape == (2, 1, 32, 32) and s["light"].shape == (2, 9, 3)
    assert _residual(s) < 1e-5
