"""The restricted unpickler: numpy, scipy sparse, chumpy stand-ins and containers; everything else refused."""

import collections
import os
import pickle
import sys
import types

import numpy as np
import pytest
import scipy.sparse as sp

from relightnet.checks import InputError
from relightnet.io.safe_pickle import MAX_DENSE, load_pickle


@pytest.mark.parametrize("protocol", range(6))
def test_arrays_sparse_and_containers_round_trip(tmp_path, protocol):
    d = {"a": np.arange(6.0).reshape(2, 3), "f": np.asfortranarray(np.arange(6, dtype=">i4").reshape(2, 3)),
         "csc": sp.csc_matrix(np.array([[0, 1.5], [2, 0]])), "csr": sp.csr_matrix(np.eye(3)),
         "coo": sp.coo_matrix(np.eye(2) * 3), "scalar": np.float32(2.5), "text": np.str_("male"), "set": {1, 2},
         "od": collections.OrderedDict(a=1), "b": b"xy", "t": (1, [2.0, None]), "empty": np.zeros((0, 4), np.uint8)}
    (tmp_path / "p.pkl").write_bytes(pickle.dumps(d, protocol=protocol))
    out = load_pickle(tmp_path / "p.pkl")
    np.testing.assert_array_equal(out["a"], d["a"])
    assert out["f"].dtype == np.int32 and np.array_equal(out["f"], d["f"])
    np.testing.assert_array_equal(out["csc"], d["csc"].toarray())
    np.testing.assert_array_equal(out["csr"], np.eye(3))
    np.testing.assert_array_equal(out["coo"], np.eye(2) * 3)
    assert out["scalar"] == np.float32(2.5) and out["scalar"].dtype == np.float32 and out["text"] == "male"
    assert out["set"] == {1, 2} and out["od"] == {"a": 1} and out["b"] == b"xy" and out["t"] == (1, [2.0, None])
    assert out["empty"].shape == (0, 4)


@pytest.mark.parametrize("protocol", (0, 1, 2))
def test_chumpy_objects_become_their_arrays_without_chumpy(tmp_path, protocol, monkeypatch):
    """Official SMPL .pkl files hold chumpy ``Ch`` objects; a stand-in class of that name makes the same pickle."""
    pkg, mod = types.ModuleType("chumpy"), types.ModuleType("chumpy.ch")

    class Ch:
        def __init__(self, x):
            self.x, self._dirty_vars, self._itr = np.asarray(x, np.float64), set(), None

    Ch.__module__, Ch.__qualname__ = "chumpy.ch", "Ch"
    mod.Ch, pkg.ch = Ch, mod
    monkeypatch.setitem(sys.modules, "chumpy", pkg)
    monkeypatch.setitem(sys.modules, "chumpy.ch", mod)
    (tmp_path / "m.pkl").write_bytes(pickle.dumps({"v": Ch(np.ones((3, 3)))}, protocol=protocol))
    monkeypatch.delitem(sys.modules, "chumpy")
    monkeypatch.delitem(sys.modules, "chumpy.ch")
    out = load_pickle(tmp_path / "m.pkl")
    assert type(out["v"]) is np.ndarray and np.array_equal(out["v"], np.ones((3, 3)))
    assert "chumpy" not in sys.modules


class _Payload:
    def __init__(self, path):
        self.path = path

    def __reduce__(self):
        return os.system, (f"touch {self.path}",)


def test_other_names_are_refused_by_name_and_nothing_runs(tmp_path):
    marker = tmp_path / "made"
    (tmp_path / "e.pkl").write_bytes(pickle.dumps({"poses": _Payload(marker)}))
    with pytest.raises(InputError, match=r"e.pkl: refused: the pickle asks for posix.system"):
        load_pickle(tmp_path / "e.pkl")
    assert not marker.exists()
    (tmp_path / "c.pkl").write_bytes(pickle.dumps({"x": collections.Counter("ab")}))
    with pytest.raises(InputError, match="collections.Counter"):
        load_pickle(tmp_path / "c.pkl")


def test_inconsistent_data_is_refused(tmp_path):
    def fails(obj, text, protocol=4):
        (tmp_path / "x.pkl").write_bytes(obj if isinstance(obj, bytes) else pickle.dumps(obj, protocol=protocol))
        with pytest.raises(InputError, match=text):
            load_pickle(tmp_path / "x.pkl")

    bad = sp.csc_matrix(np.eye(3))
    bad.indices[0] = 7
    fails(bad, "indices outside")
    big = sp.csc_matrix(np.eye(2))
    big._shape = (1 << 20, 1 << 20)
    assert (1 << 40) > MAX_DENSE
    fails(big, "larger than")
    loop: list = []
    loop.append(loop)
    fails(loop, "reference cycle")
    fails(np.array([object()], dtype=object), "not allowed|object")
    fails(b"\x80\x04junk", "not a readable pickle")
    fails(pickle.dumps(np.arange(4.0), protocol=2).replace(b"\x00\x00\x00\x00\x00\x00\x08@", b""), "needs|readable")
