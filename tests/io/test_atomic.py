"""atomic_write: all-or-nothing replacement of a file."""

import os

import pytest

from relightnet.checks import InputError
from relightnet.io import atomic_write


def test_success_replaces_and_leaves_no_temp(tmp_path):
    p = tmp_path / "f.txt"
    p.write_text("old")
    with atomic_write(p, "w") as f:
        f.write("new ✓")
        assert p.read_text() == "old"  # not visible until the block ends
    assert p.read_text(encoding="utf-8") == "new ✓"
    assert sorted(os.listdir(tmp_path)) == ["f.txt"]
    umask = os.umask(0o022)
    os.umask(umask)
    assert (p.stat().st_mode & 0o777) == (0o666 & ~umask)


def test_error_keeps_old_file_and_removes_temp(tmp_path):
    p = tmp_path / "f.bin"
    p.write_bytes(b"old")
    with pytest.raises(RuntimeError):
        with atomic_write(p) as f:
            f.write(b"partial")
            raise RuntimeError("boom")
    assert p.read_bytes() == b"old"
    assert sorted(os.listdir(tmp_path)) == ["f.bin"]
    q = tmp_path / "new.bin"
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(q) as f:
            raise KeyboardInterrupt
    assert not q.exists() and sorted(os.listdir(tmp_path)) == ["f.bin"]


def test_missing_folder_and_bad_mode(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        with atomic_write(tmp_path / "no" / "f.bin"):
            pass
    with pytest.raises(ValueError, match="mode"):
        with atomic_write(tmp_path / "f.bin", "a"):
            pass
