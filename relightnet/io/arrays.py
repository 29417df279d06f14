"""``.npy`` / ``.npz`` files read with bounded memory and one error for every way they can be wrong.

Each array's header (shape, dtype) is read first and checked against the bytes that are
really there (a file cannot claim a terabyte array) and against
:func:`~relightnet.io.limits.max_array_bytes` (a small compressed member cannot expand
without limit); then the data is read into exactly that array. Object arrays (pickles)
are never read.
"""

from __future__ import annotations

import math
import zipfile
from pathlib import Path
from typing import IO

import numpy as np

from ..checks import InputError
from .limits import max_array_bytes

__all__ = ["read_npy", "read_npz", "read_npz_names"]

_KINDS = "biufcSU"


def _header(f: IO[bytes], what: str) -> tuple[tuple[int, ...], bool, np.dtype]:
    """(shape, fortran_order, dtype) of the ``.npy`` stream ``f``, positioned at its data."""
    fmt = np.lib.format
    try:
        version = fmt.read_magic(f)
        if version == (1, 0):
            shape, fortran, dtype = fmt.read_array_header_1_0(f)
        elif version == (2, 0):
            shape, fortran, dtype = fmt.read_array_header_2_0(f)
        else:
            raise ValueError(f"npy version {version} not read")
    except InputError:
        raise
    except Exception as e:  # bad magic, header text, dtype description
        raise InputError(f"{what}: not a readable .npy array ({type(e).__name__}: {_first_line(e)})") from None
    if not isinstance(shape, tuple) or not all(isinstance(n, int) and n >= 0 for n in shape):
        raise InputError(f"{what}: bad array shape {shape!r} in the .npy header")
    if dtype.hasobject or dtype.kind not in _KINDS or dtype.fields is not None or dtype.itemsize == 0:
        raise InputError(f"{what}: array dtype {dtype} is not read (numbers and strings only)")
    return tuple(int(n) for n in shape), bool(fortran), dtype


def _first_line(e: BaseException) -> str:
    lines = str(e).strip().splitlines()
    return lines[0][:200] if lines else "no detail"


def _limit(max_bytes: int | None) -> tuple[int, str]:
    """(bytes, how to raise it): the global limit, or a reader's own when lower."""
    limit = max_array_bytes()
    if max_bytes is not None and max_bytes < limit:
        return int(max_bytes), "this reader's limit"
    return limit, "RELIGHTNET_MAX_ARRAY_BYTES"


def _gib(n: int) -> str:
    return f"{n / 2**30:.1f} GiB" if n >= 2**30 else f"{n / 2**20:.1f} MiB"


def _read_data(f: IO[bytes], shape, fortran: bool, dtype: np.dtype, available: int, what: str,
               max_bytes: int | None = None) -> np.ndarray:
    nbytes = math.prod(shape) * dtype.itemsize
    if nbytes > available:
        raise InputError(f"{what}: header says {shape} {dtype} ({nbytes} bytes) but the file holds {available}")
    limit, how = _limit(max_bytes)
    if nbytes > limit:
        raise InputError(f"{what}: array {shape} {dtype} needs {_gib(nbytes)}, above the limit of "
                         f"{_gib(limit)} ({how})")
    data = f.read(nbytes)
    if len(data) != nbytes:
        raise InputError(f"{what}: truncated array data ({len(data)} of {nbytes} bytes)")
    arr = np.frombuffer(data, dtype=dtype).reshape(shape, order="F" if fortran else "C")
    return arr.astype(dtype.newbyteorder("="))  # a native-order copy (torch reads no other)


def read_npy(path: str | Path, what: str = "array file", max_bytes: int | None = None) -> np.ndarray:
    """Read one ``.npy`` array.

    ``max_bytes``: a reader's own limit on the array's bytes, when lower than the global one.

    Raises:
        InputError: missing file, bad header, object dtype, size beyond the file or the limit.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such {what}")
    size = path.stat().st_size
    with open(path, "rb") as f:
        shape, fortran, dtype = _header(f, f"{path}")
        return _read_data(f, shape, fortran, dtype, size - f.tell(), f"{path}", max_bytes)


def read_npz_names(path: str | Path) -> list[str]:
    """The array names an ``.npz`` holds (read from its zip directory only)."""
    try:
        with zipfile.ZipFile(path) as z:
            return [i.filename[:-4] for i in z.infolist() if i.filename.endswith(".npy")]
    except Exception as e:
        raise InputError(f"{path}: unreadable .npz ({type(e).__name__}: {_first_line(e)})") from None


def read_npz(path: str | Path, what: str = "array file", names=None,
             max_bytes: int | None = None) -> dict[str, np.ndarray]:
    """Read the arrays of an ``.npz`` (all, or those of ``names`` that it has).

    ``max_bytes``: a reader's own limit on the arrays' bytes together (checked from the zip
    directory and each array's header before reading), when lower than the global one.

    Returns:
        ``{name: array}``; a name in ``names`` that the file lacks is simply absent.

    Raises:
        InputError: missing file, not a zip, a member that is not a readable array, arrays
            above :func:`~relightnet.io.limits.max_array_bytes` together; the message names the file.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such {what}")
    out: dict[str, np.ndarray] = {}
    try:
        with zipfile.ZipFile(path) as z:
            members = {i.filename[:-4]: i for i in z.infolist() if i.filename.endswith(".npy")}
            wanted = list(members) if names is None else [n for n in names if n in members]
            total = sum(members[n].file_size for n in wanted)
            limit, how = _limit(max_bytes)
            if total > limit:
                raise InputError(f"{path}: its arrays expand to {_gib(total)}, above the limit of "
                                 f"{_gib(limit)} ({how})")
            for name in wanted:
                info = members[name]
                where = f"{path}: {name!r}"
                with z.open(info) as f:
                    shape, fortran, dtype = _header(f, where)
                    out[name] = _read_data(f, shape, fortran, dtype, info.file_size - f.tell(), where, limit)
    except InputError:
        raise
    except Exception as e:  # bad zip directory, CRC, deflate stream, ...
        raise InputError(f"{path}: unreadable {what} ({type(e).__name__}: {_first_line(e)})") from None
    return out
