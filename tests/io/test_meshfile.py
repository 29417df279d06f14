"""Mesh files are bounded before trimesh parses them: size, faces, zips, referenced files."""

from __future__ import annotations

import os
import struct
import zipfile

import pytest

from relightnet.checks import InputError
from relightnet.io.meshfile import MAX_MESH_BYTES, MAX_MESH_FACES, check_mesh_file, mesh_resolver

TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


def _stl(n: int) -> bytes:
    return bytes(80) + struct.pack("<I", n) + bytes(50 * n)


def test_valid_meshes_pass(tmp_path):
    (tmp_path / "t.obj").write_text(TRI)
    assert check_mesh_file(tmp_path / "t.obj") == len(TRI)
    (tmp_path / "t.stl").write_bytes(_stl(3))
    check_mesh_file(tmp_path / "t.stl")
    with zipfile.ZipFile(tmp_path / "m.zip", "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("t.obj", TRI)
    assert check_mesh_file(tmp_path / "m.zip") == len(TRI)


def test_header_counts_and_sizes_are_checked(tmp_path):
    (tmp_path / "lie.stl").write_bytes(bytes(80) + struct.pack("<I", 10**9))
    with pytest.raises(InputError, match="lie.stl: a binary STL of 84 bytes cannot hold"):
        check_mesh_file(tmp_path / "lie.stl")
    ply = f"ply\nformat binary_little_endian 1.0\nelement vertex 3\nelement face {MAX_MESH_FACES + 1}\nend_header\n"
    (tmp_path / "big.ply").write_text(ply)
    with pytest.raises(InputError, match=f"big.ply: {MAX_MESH_FACES + 1} faces"):
        check_mesh_file(tmp_path / "big.ply")
    with open(tmp_path / "huge.obj", "wb") as f:
        f.truncate(MAX_MESH_BYTES + 1)
    with pytest.raises(InputError, match="huge.obj: a file of 64.0 MiB"):
        check_mesh_file(tmp_path / "huge.obj")


def test_zips_are_counted_from_their_directory(tmp_path):
    with zipfile.ZipFile(tmp_path / "bomb.zip", "w", zipfile.ZIP_DEFLATED) as z, \
            z.open("m.stl", "w", force_zip64=True) as f:
        f.write(bytes(80) + struct.pack("<I", 2_000_000))
        for _ in range(20):
            f.write(bytes(5_000_000))
    assert os.path.getsize(tmp_path / "bomb.zip") < 1_000_000
    with pytest.raises(InputError, match="bomb.zip: a zip whose members expand"):
        check_mesh_file(tmp_path / "bomb.zip")
    with zipfile.ZipFile(tmp_path / "faces.zip", "w") as z:
        z.writestr("m.stl", bytes(80) + struct.pack("<I", MAX_MESH_FACES + 1))
    with pytest.raises(InputError, match="faces.zip: m.stl: a binary STL"):
        check_mesh_file(tmp_path / "faces.zip")
    with zipfile.ZipFile(tmp_path / "nest.zip", "w") as z:
        z.writestr("inner.zip", b"PK\x05\x06" + bytes(18))
    with pytest.raises(InputError, match="inner.zip: an archive inside the zip"):
        check_mesh_file(tmp_path / "nest.zip")


def test_only_regular_files_inside_the_folder_are_read(tmp_path):
    os.mkfifo(tmp_path / "pipe.obj")
    with pytest.raises(InputError, match="pipe.obj: not a regular file"):
        check_mesh_file(tmp_path / "pipe.obj")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "t.obj").write_text(TRI)
    (tmp_path / "sub" / "ok.mtl").write_text("newmtl a\n")
    (tmp_path / "secret.txt").write_text("outside")
    os.mkfifo(tmp_path / "sub" / "pipe.mtl")
    resolver = mesh_resolver(tmp_path / "sub" / "t.obj")
    assert resolver.get("ok.mtl") == b"newmtl a\n"
    with pytest.raises(InputError, match="refers to pipe.mtl, which is not a regular file"):
        resolver.get("pipe.mtl")
    with pytest.raises(ValueError):
        resolver.get("../secret.txt")
    with pytest.raises(FileNotFoundError):
        resolver.get("missing.png")
    small = mesh_resolver(tmp_path / "sub" / "t.obj", used=MAX_MESH_BYTES - 4)
    with pytest.raises(InputError, match="with the files it refers to"):
        small.get("ok.mtl")
