import shutil

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.color import srgb_to_linear
from relightnet.data.preview import contact_sheet, preview, preview_columns
from relightnet.data.shards import read_shard
from relightnet.io import read_image

COLUMNS = ["image", "composite", "albedo", "shading", "mask", "normals", "T dc", "T l=1", "T l=2", "occlusion"]


@pytest.fixture(scope="module")
def root(tiny_dataset, tmp_path_factory):
    """A copy of the session's tiny dataset (6 train samples in shards of 4 + 2, 3 test; 32²)."""
    d = tmp_path_factory.mktemp("preview") / "ds"
    shutil.copytree(tiny_dataset, d)
    return d


def test_preview_png(root, tmp_path):
    out = preview(root, tmp_path / "sheet.png", n=3)
    img = read_image(out)
    assert img.shape == (3 * 32, len(COLUMNS) * 32, 3)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sheet.png"]
    # Every row shows a person: the mask column has coverage, the image column has light where the mask is.
    for r in range(3):
        tile = lambda c: img[r * 32:(r + 1) * 32, c * 32:(c + 1) * 32]  # noqa: E731, B023
        mask = tile(COLUMNS.index("mask"))[..., 0] > 0.5
        assert 10 < int(mask.sum()) < 32 * 32
        assert tile(0)[mask].mean() > 0.05 and tile(0)[~mask].max() == 0
    # Rows continue across shards; fewer samples than asked: one row per sample.
    assert read_image(preview(root, tmp_path / "all.png", n=8)).shape[0] == 6 * 32
    # The default output goes in the folder; another split.
    assert read_image(preview(root, n=8, split="test")).shape[0] == 3 * 32 and (root / "preview.png").is_file()


def test_columns_of_one_sample(root):
    a = read_shard(root / "train-00000.npz")
    s = {k: v[0] for k, v in a.items() if k != "meta"}
    cols = preview_columns(s)
    assert [n for n, _ in cols] == COLUMNS
    assert all(t.shape == (32, 32, 3) and float(t.min()) >= 0 and float(t.max()) <= 1 for _, t in cols)
    # The shading column is T·L times one exposure (sRGB-encoded).
    shading = torch.as_tensor(np.einsum("hwk,kc->hwc", s["transport"], s["light"]))
    lin = srgb_to_linear(dict(cols)["shading"])
    ok = (torch.as_tensor(s["mask"])[..., None] > 0) & (lin < 0.99) & (shading > 1e-3)
    ratio = lin[ok] / shading[ok]
    assert ok.sum() > 30 and float(ratio.std() / ratio.mean()) < 1e-3
    sheet, names = contact_sheet([s, s])
    assert sheet.shape == (64, 320, 3) and names == COLUMNS
    no_extra = {k: s[k] for k in ("image", "mask", "transport", "light")}
    assert [n for n, _ in preview_columns(no_extra)] == ["image", "shading", "mask", "T dc", "T l=1", "T l=2"]


def test_bad_preview(root, tmp_path):
    with pytest.raises(InputError, match="expected a .png"):
        preview(root, tmp_path / "x.jpg")
    with pytest.raises(InputError, match="no finished shards"):
        preview(root, tmp_path / "x.png", split="val")
    with pytest.raises(InputError, match="not found"):
        preview(tmp_path / "none", tmp_path / "x.png")
    assert list(tmp_path.iterdir()) == []
