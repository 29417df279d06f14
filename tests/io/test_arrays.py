"""relightnet.io.arrays: .npy/.npz read with bounded memory, object arrays refused, errors naming the file."""

import io
import zipfile

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.io.arrays import read_npy, read_npz, read_npz_names


def test_round_trips_of_every_kind_and_order(tmp_path):
    arrays = {"f": np.arange(12, dtype=np.float32).reshape(3, 4), "i": np.array([1, -2], np.int64),
              "b": np.array([True, False]), "u": np.array(["walk", "turn"]), "s": np.array(3.5),
              "fortran": np.asfortranarray(np.arange(6.0).reshape(2, 3)), "be": np.arange(3, dtype=">f8")}
    np.savez_compressed(tmp_path / "a.npz", **arrays)
    got = read_npz(tmp_path / "a.npz")
    assert set(got) == set(arrays) == set(read_npz_names(tmp_path / "a.npz"))
    for k, v in arrays.items():
        assert np.array_equal(got[k], v) and got[k].shape == v.shape, k
    assert got["be"].dtype.byteorder in ("=", "<", "|")  # native order, as torch needs
    assert set(read_npz(tmp_path / "a.npz", names=("f", "missing"))) == {"f"}
    np.save(tmp_path / "x.npy", arrays["fortran"])
    assert np.array_equal(read_npy(tmp_path / "x.npy"), arrays["fortran"])


def test_object_arrays_and_lying_headers_are_refused(tmp_path):
    np.save(tmp_path / "obj.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(InputError, match="obj.npy: array dtype object is not read"):
        read_npy(tmp_path / "obj.npy")
    np.save(tmp_path / "big.npy", np.zeros(1000, np.float64))
    data = (tmp_path / "big.npy").read_bytes()
    (tmp_path / "cut.npy").write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=r"cut.npy: header says \(1000,\) float64 \(8000 bytes\) but the file holds"):
        read_npy(tmp_path / "cut.npy")
    (tmp_path / "text.npy").write_bytes(b"not an array")
    with pytest.raises(InputError, match="text.npy: not a readable .npy array"):
        read_npy(tmp_path / "text.npy")
    with pytest.raises(InputError, match="missing.npz: no such light file"):
        read_npz(tmp_path / "missing.npz", "light file")
    (tmp_path / "nozip.npz").write_bytes(b"PK but no zip")
    with pytest.raises(InputError, match="nozip.npz: unreadable .npz"):
        read_npz_names(tmp_path / "nozip.npz")


def test_the_memory_limit_counts_the_expanded_size(tmp_path, monkeypatch):
    buf = io.BytesIO()
    np.save(buf, np.zeros((256, 256), np.float64))  # 512 KiB that deflates to almost nothing
    with zipfile.ZipFile(tmp_path / "bomb.npz", "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("a.npy", buf.getvalue())
    assert (tmp_path / "bomb.npz").stat().st_size < 10_000
    monkeypatch.setenv("RELIGHTNET_MAX_ARRAY_BYTES", "100000")
    with pytest.raises(InputError, match="bomb.npz: its arrays expand to .* above the limit"):
        read_npz(tmp_path / "bomb.npz")
    monkeypatch.setenv("RELIGHTNET_MAX_ARRAY_BYTES", str(2**20))
    assert read_npz(tmp_path / "bomb.npz")["a"].shape == (256, 256)
