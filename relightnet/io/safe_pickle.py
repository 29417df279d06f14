"""Pickles from strangers, read without running anything they name.

:func:`load_pickle` reads the pickles relightnet accepts (SMPL model files, SMPL-style
motion files) through an unpickler whose ``find_class`` knows a short list of names and
hands out *stand-ins* for them, never the real classes or functions:

- numpy arrays, scalars and dtypes (``numpy[._]core.multiarray._reconstruct`` / ``scalar``,
  ``numpy[._]core.numeric._frombuffer``, ``numpy.dtype``): numeric and string dtypes only,
  never object arrays; the bytes are checked against shape × itemsize;
- scipy sparse matrices (``csc``/``csr``/``coo``, ``_matrix`` or ``_array``, any scipy module
  path): indices checked, returned **dense** (at most :data:`MAX_DENSE` elements);
- chumpy ``Ch`` objects (official SMPL ``.pkl`` files hold them): replaced by the array they
  hold (``x``); chumpy is never imported;
- builtin containers (dict, list, tuple, set, frozenset, OrderedDict), numbers, strings, bytes.

Anything else is refused by name (``InputError: model.pkl: refused: the pickle asks for
os.system ...``) before it is looked up, so nothing is imported, created or called. After
loading, the stand-ins are resolved into plain numpy/Python values by this module's own
code; the result holds nothing but those.
"""

from __future__ import annotations

import collections
import io
import math
import pickle
from pathlib import Path

import numpy as np

from ..checks import InputError

__all__ = ["load_pickle", "MAX_DENSE"]

#: Largest dense array (elements) a sparse matrix may expand to.
MAX_DENSE = 1 << 26
#: Deepest container nesting accepted.
MAX_DEPTH = 64
_DTYPE_KINDS = "biufcSU"


class _Stand:
    """Base of the stand-ins: remembers the call arguments and the BUILD state, nothing more."""

    __slots__ = ("args", "state")

    def __new__(cls, *args, **kwargs):
        obj = object.__new__(cls)
        obj.args, obj.state = args, None
        return obj

    def __init__(self, *args, **kwargs) -> None:
        pass

    def __setstate__(self, state) -> None:
        self.state = state

    def __reduce__(self):  # never pickled again
        raise TypeError("stand-ins cannot be pickled")


class _ArrayType(_Stand):
    """What ``numpy.ndarray`` means inside a pickle: only a tag for ``_reconstruct``."""


class _Array(_Stand):
    """An array to be: ``_reconstruct(ndarray, shape, dtype)`` then BUILD (version, shape, dtype, fortran, data)."""


class _Dtype(_Stand):
    """``numpy.dtype(spec, align, copy)`` then BUILD (version, byteorder, ...)."""


class _Scalar(_Stand):
    """``numpy scalar(dtype, bytes)``."""


class _Buffer(_Stand):
    """``_frombuffer(buffer, dtype, shape, order)`` (pickle protocol 5 arrays)."""


class _Sparse(_Stand):
    """A scipy sparse matrix: BUILD state is its ``__dict__`` (data, indices, indptr, _shape ...)."""

    fmt = ""


class _Csc(_Sparse):
    fmt = "csc"


class _Csr(_Sparse):
    fmt = "csr"


class _Coo(_Sparse):
    fmt = "coo"


class _Chumpy(_Stand):
    """A chumpy ``Ch``: BUILD state is its ``__dict__``; only ``x`` (the array) is kept."""


class _Object(_Stand):
    """``object`` as the base argument of ``copy_reg._reconstructor``."""


def _reconstructor(cls, base=None, state=None):
    """``copy_reg._reconstructor``: only for stand-in classes."""
    if not (isinstance(cls, type) and issubclass(cls, _Stand)):
        raise pickle.UnpicklingError("copy_reg._reconstructor of a class that is not allowed")
    return cls()


def _encode(text, encoding="latin1"):
    """``_codecs.encode`` as protocol-2 pickles of bytes use it (latin-1 only)."""
    if not isinstance(text, str) or str(encoding).lower().replace("_", "-") not in ("latin1", "latin-1"):
        raise pickle.UnpicklingError("_codecs.encode other than str → latin-1 bytes")
    return text.encode("latin1")


def _bytes(source=b"", encoding="latin1"):
    """``bytes(...)`` as protocol-0/1 pickles use it: from a list of ints or a latin-1 str (never a size)."""
    if isinstance(source, str):
        return _encode(source, encoding)
    if isinstance(source, (list, tuple, bytes, bytearray)):
        return bytes(source)
    raise pickle.UnpicklingError("bytes() of something other than a list or str")


def _allowed() -> dict[tuple[str, str], object]:
    table: dict[tuple[str, str], object] = {("numpy", "ndarray"): _ArrayType, ("numpy", "dtype"): _Dtype}
    for core in ("numpy.core", "numpy._core"):
        table[(f"{core}.multiarray", "_reconstruct")] = _Array
        table[(f"{core}.multiarray", "scalar")] = _Scalar
        table[(f"{core}.numeric", "_frombuffer")] = _Buffer
    for b in ("builtins", "__builtin__"):
        table.update({(b, "set"): set, (b, "frozenset"): frozenset, (b, "object"): _Object, (b, "bytes"): _bytes})
    table[("collections", "OrderedDict")] = collections.OrderedDict
    table[("_codecs", "encode")] = _encode
    table[("copy_reg", "_reconstructor")] = table[("copyreg", "_reconstructor")] = _reconstructor
    for fmt, cls in (("csc", _Csc), ("csr", _Csr), ("coo", _Coo)):
        for mod in ("scipy.sparse", f"scipy.sparse.{fmt}", f"scipy.sparse._{fmt}"):
            for kind in ("matrix", "array"):
                table[(mod, f"{fmt}_{kind}")] = cls
    table[("chumpy.ch", "Ch")] = table[("chumpy", "Ch")] = _Chumpy
    return table


_ALLOWED = _allowed()


class _Unpickler(pickle.Unpickler):
    def __init__(self, data: bytes, name: str) -> None:
        super().__init__(io.BytesIO(data), encoding="latin1")
        self._name = name

    def find_class(self, module: str, name: str):
        found = _ALLOWED.get((module, name))
        if found is None:
            raise InputError(
                f"{self._name}: refused: the pickle asks for {module}.{name} (only numpy arrays, scipy sparse "
                "matrices, chumpy arrays and builtin containers are read; nothing in it was run)"
            )
        return found

    def persistent_load(self, pid):
        raise pickle.UnpicklingError("persistent ids are not allowed")


def load_pickle(path: str | Path, what: str = "pickle") -> object:
    """Read a pickle file without running code from it.

    Args:
        path: the ``.pkl`` file.
        what: what the file should be, for messages (``"SMPL model file"``).

    Returns:
        Plain values: dicts, lists, tuples, sets, numbers, strings, bytes and numpy arrays /
        scalars (numeric or string dtypes, native byte order); sparse matrices come back dense,
        chumpy objects as their arrays.

    Raises:
        InputError: missing or unreadable file, a name outside the allowed list (the message
            names it), inconsistent array data, a reference cycle or too deep nesting.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such {what}")
    data = path.read_bytes()
    try:
        raw = _Unpickler(data, path.name).load()
    except InputError:
        raise
    except Exception as e:  # every malformed stream: truncated, bad opcodes, wrong argument types
        raise InputError(f"{path.name}: not a readable {what} ({type(e).__name__}: {_short(e)})") from None
    return _Resolver(path.name).value(raw)


def _short(e: BaseException) -> str:
    text = str(e).strip().splitlines()
    return text[0][:200] if text else "no detail"


class _Resolver:
    """Turns the unpickled graph (with stand-ins) into plain values, checking everything."""

    def __init__(self, name: str) -> None:
        self.name, self.done, self.open = name, {}, set()

    def fail(self, why: str) -> InputError:
        return InputError(f"{self.name}: {why}")

    def value(self, obj, depth: int = 0):
        if obj is None or isinstance(obj, (bool, int, float, complex, str, bytes)):
            return obj
        if isinstance(obj, (np.ndarray, np.generic)):
            return obj
        key = id(obj)
        if key in self.done:
            return self.done[key]
        if key in self.open:
            raise self.fail("the pickle holds a reference cycle")
        if depth > MAX_DEPTH:
            raise self.fail(f"containers nested deeper than {MAX_DEPTH}")
        self.open.add(key)
        try:
            out = self._convert(obj, depth + 1)
        finally:
            self.open.discard(key)
        self.done[key] = out
        return out

    def _convert(self, obj, depth: int):
        if isinstance(obj, _Stand):
            return self._stand(obj, depth)
        if isinstance(obj, dict):  # dict and OrderedDict
            out = {}
            for k, v in obj.items():
                k = self.value(k, depth)
                try:
                    out[k] = self.value(v, depth)
                except TypeError:
                    raise self.fail(f"an unhashable dict key ({type(k).__name__})") from None
            return out
        if isinstance(obj, (list, tuple)):
            return type(obj)(self.value(v, depth) for v in obj)
        if isinstance(obj, (set, frozenset)):
            try:
                return type(obj)(self.value(v, depth) for v in obj)
            except TypeError:
                raise self.fail("an unhashable set member") from None
        if isinstance(obj, bytearray):
            return bytes(obj)
        raise self.fail(f"unexpected {type(obj).__name__} object in the pickle")

    def _stand(self, obj: _Stand, depth: int):
        if isinstance(obj, _Array):
            return self._array(obj, depth)
        if isinstance(obj, _Buffer):
            args = obj.args
            if len(args) < 3 or not isinstance(args[0], (bytes, bytearray)):
                raise self.fail("a numpy buffer without its bytes")
            order = args[3] if len(args) > 3 else "C"
            return self._from_bytes(args[0], self.dtype(args[1], depth), args[2], order == "F")
        if isinstance(obj, _Scalar):
            if len(obj.args) != 2:
                raise self.fail("a numpy scalar without (dtype, bytes)")
            dt = self.dtype(obj.args[0], depth)
            return self._from_bytes(obj.args[1], dt, (), False)[()]
        if isinstance(obj, _Dtype):
            return self.dtype(obj, depth)
        if isinstance(obj, _Sparse):
            return self._sparse(obj, depth)
        if isinstance(obj, _Chumpy):
            st = obj.state
            x = st.get("x") if isinstance(st, dict) else None
            x = self.value(x, depth)
            if not isinstance(x, np.ndarray):
                raise self.fail("a chumpy object without an array 'x' (expressions are not read; save the "
                                "evaluated arrays)")
            return x
        raise self.fail(f"{type(obj).__name__.strip('_').lower()} used outside an array")

    def dtype(self, obj, depth: int) -> np.dtype:
        if not isinstance(obj, _Dtype) or not obj.args or not isinstance(obj.args[0], str):
            raise self.fail("a numpy dtype that is not a plain type name")
        spec = obj.args[0]
        try:
            dt = np.dtype(spec)
        except (TypeError, ValueError):
            raise self.fail(f"unknown numpy dtype {spec[:40]!r}") from None
        st = obj.state
        if isinstance(st, tuple) and len(st) > 1 and st[1] in ("<", ">") and dt.itemsize > 1:
            dt = dt.newbyteorder(st[1])
        if isinstance(st, tuple) and len(st) > 4 and (st[3] is not None or st[4] is not None):
            raise self.fail("structured numpy dtypes are not read")
        if dt.kind not in _DTYPE_KINDS or dt.hasobject or dt.fields is not None or dt.itemsize == 0:
            raise self.fail(f"numpy dtype {dt} is not allowed (numbers and strings only)")
        return dt

    def _array(self, obj: _Array, depth: int) -> np.ndarray:
        st = obj.state
        if not obj.args or obj.args[0] is not _ArrayType:
            raise self.fail("numpy _reconstruct of something other than ndarray")
        if not isinstance(st, tuple) or len(st) != 5:
            raise self.fail("a numpy array without its (version, shape, dtype, fortran, data) state")
        _, shape, dt, fortran, raw = st
        return self._from_bytes(raw, self.dtype(dt, depth), shape, bool(fortran))

    def _from_bytes(self, raw, dt: np.dtype, shape, fortran: bool) -> np.ndarray:
        if isinstance(raw, str):  # Python 2 str decoded as latin-1
            raw = raw.encode("latin1")
        if isinstance(raw, list):
            raise self.fail("numpy object arrays are not read")
        if not isinstance(raw, (bytes, bytearray)):
            raise self.fail(f"numpy array data is {type(raw).__name__}, expected bytes")
        if isinstance(shape, int):
            shape = (shape,)
        if not isinstance(shape, (tuple, list)) or not all(isinstance(n, int) and n >= 0 for n in shape):
            raise self.fail(f"a numpy array with a bad shape {str(shape)[:60]}")
        shape = tuple(shape)
        if len(raw) != math.prod(shape) * dt.itemsize:
            raise self.fail(f"a numpy array {shape} of {dt} needs {math.prod(shape) * dt.itemsize} bytes, "
                            f"has {len(raw)}")
        arr = np.frombuffer(bytes(raw), dtype=dt).reshape(shape, order="F" if fortran else "C")
        return arr.astype(dt.newbyteorder("="))  # a native-order copy

    def _sparse(self, obj: _Sparse, depth: int) -> np.ndarray:
        st = obj.state
        if not isinstance(st, dict):
            raise self.fail(f"a sparse {obj.fmt} matrix without its arrays")
        shape = st.get("_shape", st.get("shape"))
        if (not isinstance(shape, tuple) or len(shape) != 2
                or not all(isinstance(n, int) and 0 <= n for n in shape)):
            raise self.fail(f"a sparse {obj.fmt} matrix with a bad shape {str(shape)[:60]}")
        if math.prod(shape) > MAX_DENSE:
            raise self.fail(f"a sparse matrix {shape} is larger than {MAX_DENSE} elements dense")

        def arr(key, kind):
            a = self.value(st.get(key), depth)
            if not isinstance(a, np.ndarray) or a.ndim != 1 or a.dtype.kind not in kind:
                raise self.fail(f"a sparse {obj.fmt} matrix whose {key!r} is not a 1-D array")
            return a

        data = arr("data", "biuf")
        if obj.fmt == "coo":
            if "coords" in st:
                coords = self.value(st["coords"], depth)
                if not isinstance(coords, tuple) or len(coords) != 2:
                    raise self.fail("a sparse coo matrix whose 'coords' is not (row, col)")
                st = dict(st, row=coords[0], col=coords[1])
            rows, cols = arr("row", "iu"), arr("col", "iu")
        else:
            major, minor = shape if obj.fmt == "csr" else shape[::-1]
            indices, indptr = arr("indices", "iu"), arr("indptr", "iu").astype(np.int64)
            if len(indptr) != major + 1 or indptr[0] != 0 or (np.diff(indptr) < 0).any() \
                    or indptr[-1] > len(indices):
                raise self.fail(f"a sparse {obj.fmt} matrix with an inconsistent 'indptr'")
            lead = np.repeat(np.arange(major), np.diff(indptr))
            indices = indices[: indptr[-1]]
            rows, cols = (lead, indices) if obj.fmt == "csr" else (indices, lead)
        if not len(rows) == len(cols) <= len(data):
            raise self.fail(f"a sparse {obj.fmt} matrix with more indices than values")
        rows, cols = rows.astype(np.int64), cols.astype(np.int64)
        if len(rows) and (rows.max() >= shape[0] or cols.max() >= shape[1] or min(rows.min(), cols.min()) < 0):
            raise self.fail(f"a sparse {obj.fmt} matrix with indices outside {shape}")
        dense = np.zeros(shape, dtype=np.result_type(data.dtype, np.float32))
        np.add.at(dense, (rows, cols), data[: len(rows)])
        return dense
