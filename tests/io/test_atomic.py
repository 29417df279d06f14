"""atomic_write: all-or-nothing replacement of a file."""

import os
from pathlib import Path

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


def _killed_writer(path, tag=""):
    """The temporary file a writer killed mid-write leaves: made by a child process that is gone."""
    import subprocess
    import sys

    code = ("import sys; from relightnet.io.atomic import temp_path; p = temp_path(sys.argv[1], sys.argv[2]); "
            "p.write_bytes(b'partial'); print(p)")
    out = subprocess.run([sys.executable, "-c", code, str(path), tag], capture_output=True, text=True, check=True)
    return Path(out.stdout.strip())


@pytest.mark.slow
def test_next_writer_removes_temp_files_of_dead_writers_only(tmp_path):
    from relightnet.io.atomic import remove_stale, temp_path

    out = tmp_path / "out.mp4"
    dead, dead_stage = _killed_writer(out), _killed_writer(out, "stage")
    assert dead.is_file() and dead.name.startswith(".out.mp4.") and dead.name.endswith(".tmp")
    alive = temp_path(out)  # this process: still running
    alive.write_bytes(b"mine")
    other_host = tmp_path / ".out.mp4.elsewhere.1-1.abcd.tmp"
    old_style = tmp_path / ".out.mp4.k3j4h5.tmp"  # no writer recorded: left alone
    other_file = _killed_writer(tmp_path / "other.mp4")
    for p in (other_host, old_style):
        p.write_bytes(b"?")
    with atomic_write(out) as f:
        f.write(b"complete")
    assert out.read_bytes() == b"complete"
    assert not dead.exists() and not dead_stage.exists()
    assert alive.exists() and other_host.exists() and old_style.exists() and other_file.exists()
    assert remove_stale(tmp_path / "other.mp4") == [other_file]
    alive.unlink()


def test_temp_names_record_the_writer(tmp_path):
    from relightnet.io.atomic import temp_path

    a, b = temp_path(tmp_path / "x.png"), temp_path(tmp_path / "x.png", "video")
    assert a != b and a.parent == tmp_path and f".{os.getpid()}-" in a.name and ".video." in b.name
    with pytest.raises(ValueError, match="letters"):
        temp_path(tmp_path / "x.png", "a.b")


def test_a_long_output_name_gets_a_temporary_name_that_fits(tmp_path):
    """A valid 251-character name: its temporary name is cut (with a hash) to 255 bytes, and found again."""
    from relightnet.io.atomic import remove_stale, temp_path

    name = "é" * 100 + "a" * 47 + ".png"  # 251 bytes
    assert len(os.fsencode(name)) == 251
    with atomic_write(tmp_path / name) as f:
        f.write(b"x")
    assert (tmp_path / name).read_bytes() == b"x" and os.listdir(tmp_path) == [name]
    tmp = temp_path(tmp_path / name, "video")
    assert len(os.fsencode(tmp.name)) <= 255 and tmp.name.endswith(".tmp")
    dead = tmp.with_name(tmp.name.replace(f".{os.getpid()}-", ".999999999-"))
    dead.write_bytes(b"")
    assert remove_stale(tmp_path / name) == [dead]


@pytest.mark.slow
def test_a_full_disk_names_the_file(tmp_path):
    """ENOSPC / EFBIG while writing: the error names the output (here: a file-size limit in a child)."""
    import subprocess
    import sys

    script = (
        "import resource, signal, sys\n"
        "from relightnet.io import atomic_write\n"
        "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (1000, 1000))\n"
        "try:\n"
        "    with atomic_write(sys.argv[1]) as f:\n"
        "        f.write(bytes(5000))\n"
        "except OSError as e:\n"
        "    print(e.filename, e.errno)\n"
    )
    out = tmp_path / "out.bin"
    proc = subprocess.run([sys.executable, "-c", script, str(out)], capture_output=True, text=True, check=True)
    import errno

    assert proc.stdout.split() == [str(out), str(errno.EFBIG)]
    assert os.listdir(tmp_path) == []
