"""Mesh files from strangers: bounded before trimesh reads them.

trimesh reads whatever a file says: a 1.5 MB zip can hold a 10-million-face STL, a binary
STL or PLY header can claim any count, and an OBJ's ``mtllib`` or a glTF's buffer ``uri``
can name a FIFO beside the mesh (reading it never returns). Before :func:`trimesh.load`:

- the mesh is a regular file of at most :data:`MAX_MESH_BYTES`; a zip's members together
  (uncompressed, from its directory) too, and a zip inside a zip is refused;
- a binary STL's and a PLY's face count (their headers) is at most :data:`MAX_MESH_FACES`
  (and a binary STL's size agrees with its count);
- files the mesh refers to (materials, textures, buffers) are read through
  :func:`mesh_resolver`: regular files inside the mesh's folder only, within the same
  byte budget.

After loading, the caller checks the face count again (:func:`check_face_count`).
"""

from __future__ import annotations

import os
import re
import stat
import struct
import zipfile
from pathlib import Path

from ..errors import InputError

__all__ = ["MAX_MESH_BYTES", "MAX_MESH_FACES", "check_mesh_file", "mesh_resolver", "check_face_count"]

#: Largest mesh file (or zip content, uncompressed, plus referenced files) read, in bytes.
MAX_MESH_BYTES = 64 << 20
#: Most triangles of a mesh (from its header where the format has one, and after loading).
MAX_MESH_FACES = 1_000_000
_ARCHIVES = (".zip", ".tar", ".gz", ".tgz", ".bz2", ".xz", ".7z")


def _regular_size(path: Path, what: str) -> int:
    try:
        st = os.stat(path)
    except OSError:
        raise InputError(f"{path}: {what} not found") from None
    if not stat.S_ISREG(st.st_mode):
        raise InputError(f"{path}: not a regular file; expected a {what}")
    return st.st_size


def _too_big(path, size: int, what: str) -> InputError:
    return InputError(f"{path}: {what} of {size / 2**20:.1f} MiB; meshes of at most {MAX_MESH_BYTES >> 20} MiB "
                      f"are read (relightnet.io.meshfile.MAX_MESH_BYTES)")


def _faces_from_header(head: bytes, size: int, name: str) -> int | None:
    """The face count a binary STL or a PLY header states (None for other formats)."""
    lower = name.lower()
    if lower.endswith(".stl") and len(head) >= 84 and not head[:5].lower() == b"solid":
        n = struct.unpack("<I", head[80:84])[0]
        if size != 84 + 50 * n:
            raise InputError(f"{name}: a binary STL of {size} bytes cannot hold the {n} faces its header states")
        return n
    if lower.endswith(".ply") and head.startswith(b"ply"):
        m = re.search(rb"\nelement face (\d+)", head[:1 << 16])
        return int(m.group(1)) if m else None
    return None


def _check_faces(n: int | None, name: str) -> None:
    if n is not None and n > MAX_MESH_FACES:
        raise InputError(f"{name}: {n} faces; meshes of at most {MAX_MESH_FACES} faces are read "
                         "(relightnet.io.meshfile.MAX_MESH_FACES)")


def check_mesh_file(path: str | os.PathLike) -> int:
    """Refuse a mesh (or zip of meshes) above the limits before anything is parsed.

    Returns:
        The bytes it will take to read (file, or the zip's members uncompressed).

    Raises:
        InputError: naming the file (or ``zip: member``) and the limit.
    """
    path = Path(path)
    size = _regular_size(path, "mesh file")
    if size > MAX_MESH_BYTES:
        raise _too_big(path, size, "a file")
    if not zipfile.is_zipfile(path):
        with open(path, "rb") as f:
            _check_faces(_faces_from_header(f.read(1 << 16), size, str(path)), str(path))
        return size
    try:
        with zipfile.ZipFile(path) as z:
            infos = [i for i in z.infolist() if not i.is_dir()]
            total = sum(i.file_size for i in infos)
            if total > MAX_MESH_BYTES:
                raise _too_big(path, total, "a zip whose members expand to a total")
            for i in infos:
                where = f"{path}: {i.filename}"
                if i.filename.lower().endswith(_ARCHIVES):
                    raise InputError(f"{where}: an archive inside the zip; unpack it first")
                with z.open(i) as f:
                    _check_faces(_faces_from_header(f.read(1 << 16), i.file_size, where), where)
    except InputError:
        raise
    except Exception as e:  # noqa: BLE001 - a damaged zip directory or member
        raise InputError(f"{path}: unreadable zip of meshes ({type(e).__name__})") from None
    return total


def check_face_count(n_faces: int, path) -> None:
    """Refuse a loaded mesh above :data:`MAX_MESH_FACES` (formats whose header does not say)."""
    _check_faces(int(n_faces), str(path))


def mesh_resolver(path: str | os.PathLike, used: int = 0):
    """A trimesh resolver for the files ``path`` refers to: regular files in its folder only,
    all together within :data:`MAX_MESH_BYTES` (``used``: bytes the mesh itself takes)."""
    from trimesh.resolvers import FilePathResolver

    budget = [MAX_MESH_BYTES - used]

    class _Resolver(FilePathResolver):
        def get(self, name: str):
            target = self.absolute(name.strip())
            try:
                st = os.stat(target)
            except OSError:
                raise FileNotFoundError(name) from None
            if not stat.S_ISREG(st.st_mode):
                raise InputError(f"{path}: refers to {name!s:.100}, which is not a regular file")
            if st.st_size > budget[0]:
                raise _too_big(path, MAX_MESH_BYTES - budget[0] + st.st_size, "a mesh with the files it refers to")
            budget[0] -= st.st_size
            with open(target, "rb") as f:
                return f.read(st.st_size)

    return _Resolver(str(path))
