import os
import zipfile
from types import SimpleNamespace

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.data import SynthConfig
from relightnet.data.shards import (
    expected_fields,
    file_sha256,
    read_shard,
    read_shard_meta,
    shard_name,
    shard_plan,
    stack_samples,
    write_shard,
)


def _samples(n=3, res=8, k=9):
    rng = np.random.default_rng(0)
    return [SimpleNamespace(arrays={"image": rng.random((res, res, 3), dtype=np.float32),
                                    "parts": rng.integers(0, 5, (res, res), dtype=np.uint8),
                                    "light": rng.standard_normal((k, 3)).astype(np.float32)},
                            meta={"index": i, "light": {"kind": "envmap", "name": "studio"}, "ünï": "ok"})
            for i in range(n)]


def test_plan_names_and_fields():
    cfg = SynthConfig(res=32, shard_size=4, counts={"train": 10, "val": 4, "test": 0})
    assert shard_plan(cfg, "train") == [(0, 0, 4), (1, 4, 4), (2, 8, 2)]
    assert shard_plan(cfg, "val") == [(0, 0, 4)] and shard_plan(cfg, "test") == []
    assert shard_name("train", 3) == "train-00003.npz"
    with pytest.raises(InputError):
        shard_name("training", 0)
    f = expected_fields(cfg)
    assert f["transport"] == ((32, 32, 9), "float32") and f["light"] == ((9, 3), "float32")
    assert f["image_srgb"] == ((32, 32, 3), "uint8")
    seq = expected_fields(cfg.replace(sequence_frames=5, lmax=1))
    assert seq["transport"] == ((5, 32, 32, 4), "float32") and seq["mask"] == ((5, 32, 32), "float32")


def test_write_is_byte_reproducible_and_loadable(tmp_path):
    arrays = stack_samples(_samples())
    assert arrays["image"].shape == (3, 8, 8, 3) and arrays["meta"].shape == (3,)
    a = write_shard(tmp_path / "a.npz", arrays)
    (tmp_path / "sub").mkdir()
    b = write_shard(tmp_path / "sub" / "a.npz", dict(reversed(list(arrays.items()))))
    assert a == b and (tmp_path / "a.npz").read_bytes() == (tmp_path / "sub" / "a.npz").read_bytes()
    assert a["sha256"] == file_sha256(tmp_path / "a.npz") and a["bytes"] == os.path.getsize(tmp_path / "a.npz")
    with zipfile.ZipFile(tmp_path / "a.npz") as z:
        infos = z.infolist()
        assert [i.filename for i in infos] == ["image.npy", "light.npy", "meta.npy", "parts.npy"]
        assert all(i.date_time == (1980, 1, 1, 0, 0, 0) and i.compress_type == zipfile.ZIP_DEFLATED for i in infos)
    with np.load(tmp_path / "a.npz", allow_pickle=False) as z:  # a plain npz
        np.testing.assert_array_equal(z["parts"], arrays["parts"])
    got = read_shard(tmp_path / "a.npz")
    np.testing.assert_array_equal(got["image"], arrays["image"])
    assert got["meta"][2] == {"index": 2, "light": {"kind": "envmap", "name": "studio"}, "ünï": "ok"}
    assert read_shard_meta(tmp_path / "a.npz")[0]["index"] == 0
    assert set(read_shard(tmp_path / "a.npz", ["light"])) == {"light"}
    s = write_shard(tmp_path / "s.npz", arrays, compression="store")
    assert s["bytes"] > a["bytes"]
    np.testing.assert_array_equal(read_shard(tmp_path / "s.npz")["light"], arrays["light"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.npz", "s.npz", "sub"]  # no temporary files left


def test_deflate_stores_the_background(tmp_path):
    arrays = {**stack_samples(_samples()), "background": np.random.default_rng(0).random((3, 8, 8, 3), np.float32)}
    write_shard(tmp_path / "a.npz", arrays)
    with zipfile.ZipFile(tmp_path / "a.npz") as z:
        kinds = {i.filename: i.compress_type for i in z.infolist()}
    assert kinds.pop("background.npy") == zipfile.ZIP_STORED and set(kinds.values()) == {zipfile.ZIP_DEFLATED}
    np.testing.assert_array_equal(read_shard(tmp_path / "a.npz")["background"], arrays["background"])


def test_bad_shards(tmp_path):
    arrays = stack_samples(_samples())
    write_shard(tmp_path / "a.npz", arrays)
    with pytest.raises(InputError, match="no field"):
        read_shard(tmp_path / "a.npz", ["transport"])
    with pytest.raises(InputError, match="not found"):
        read_shard(tmp_path / "missing.npz")
    data = (tmp_path / "a.npz").read_bytes()
    (tmp_path / "t.npz").write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match="unreadable shard"):
        read_shard(tmp_path / "t.npz")
    with pytest.raises(InputError):
        write_shard(tmp_path / "o.npz", {"x": np.array([object()])})
    with pytest.raises(InputError):
        write_shard(tmp_path / "o.npz", arrays, compression="zstd")
    assert not (tmp_path / "o.npz").exists()
    with pytest.raises(InputError, match="different fields"):
        s = _samples(2)
        s[1].arrays.pop("parts")
        stack_samples(s)
