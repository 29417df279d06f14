"""Atomic file writes: a reader never sees a half-written file, a killed writer leaves no litter.

Every writer in relightnet goes through :func:`atomic_write`: data goes to a
hidden temporary file in the destination folder, is flushed and fsynced, then
``os.replace`` moves it over the destination in one step. On any error the
temporary file is deleted and the destination is left as it was.

A process killed outright (SIGKILL, power loss) cannot delete its temporary file, so
temporary names say who wrote them (:func:`temp_path`: ``.out.mp4.<host>.<pid>-<start>.<random>.tmp``)
and the next writer of the same output removes those whose process is gone
(:func:`remove_stale`): the same host, and no live process with that PID and start time.
Temporary files of running writers, of other hosts and of unknown form are left alone.
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import shutil
import socket
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from ..checks import InputError

__all__ = ["atomic_write", "temp_path", "remove_stale"]

_TEMP = re.compile(r"(?:(?P<tag>[A-Za-z]+)\.)?(?P<host>[A-Za-z0-9_-]+)\.(?P<pid>\d+)-(?P<start>\d+)\.[0-9a-f]+\.tmp")


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9_-]", "-", socket.gethostname())[:48] or "host"


def _start_time(pid: int | str) -> str | None:
    """A process's start time (clock ticks since boot, /proc/PID/stat), or None when it does not exist."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            stat = f.read()
    except OSError:
        return None
    return stat.rsplit(")", 1)[-1].split()[19]


def _writer_gone(pid: int, start: str) -> bool:
    """True when no process ``pid`` started at ``start`` runs on this host."""
    if os.path.isdir("/proc"):
        return _start_time(pid) != start
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False
    return False


def temp_path(path: str | os.PathLike, tag: str = "") -> Path:
    """A fresh hidden name beside ``path`` that records this process as its writer.

    Args:
        path: the final output.
        tag: optional letters naming the use (``"video"``, ``"stage"``).

    Returns:
        ``.{name}.[{tag}.]{host}.{pid}-{start}.{random}.tmp`` in ``path``'s folder.
    """
    path = Path(path)
    if tag and not tag.isalpha():
        raise ValueError(f"tag: expected letters only, got {tag!r}")
    pid = os.getpid()
    who = f"{tag + '.' if tag else ''}{_host()}.{pid}-{_start_time(pid) or 0}.{secrets.token_hex(4)}.tmp"
    return path.with_name(f".{_stem(path.name)}.{who}")


_NAME_MAX = 255
_LONGEST_WHO = 8 + 48 + 1 + 10 + 1 + 20 + 1 + 8 + 4  # a tag, the host, pid-start, random, .tmp


def _stem(name: str, reserved: int = _LONGEST_WHO) -> str:
    """The output's name as its temporary names start (after the dot), short enough that a
    temporary name fits in 255 bytes: a long name is cut and a hash of it added."""
    room = _NAME_MAX - 2 - reserved
    if len(os.fsencode(name)) <= room:
        return name
    import hashlib

    digest = hashlib.sha1(os.fsencode(name)).hexdigest()[:10]
    cut = os.fsencode(name)[: room - 11].decode("utf-8", "ignore")
    return f"{cut}~{digest}"


def remove_stale(path: str | os.PathLike) -> list[Path]:
    """Delete the temporary files (and staging folders) of ``path`` left by writers that are gone.

    Returns:
        The paths removed.
    """
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    prefix, host, removed = f".{_stem(path.name)}.", _host(), []
    try:
        entries = [p for p in parent.iterdir() if p.name.startswith(prefix) and p.name.endswith(".tmp")]
    except OSError:
        return removed
    for p in entries:
        m = _TEMP.fullmatch(p.name[len(prefix):])
        if m is None or m["host"] != host or not _writer_gone(int(m["pid"]), m["start"]):
            continue
        with contextlib.suppress(OSError):
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p)
            else:
                p.unlink()
            removed.append(p)
    return removed


def _umask() -> int:
    """The process umask (read without changing it when /proc allows)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    old = os.umask(0o022)
    os.umask(old)
    return old


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike, mode: str = "wb") -> Iterator[IO]:
    """Open a temporary file that replaces ``path`` when the block succeeds.

    Args:
        path: destination file; its folder must exist.
        mode: ``"wb"`` (bytes) or ``"w"`` (UTF-8 text).

    Yields:
        The open temporary file object.

    Raises:
        InputError: the destination folder does not exist or is not a folder.

    Example:
        >>> with atomic_write("light.json", "w") as f:
        ...     _ = f.write("{}")
        >>> Path("light.json").read_text()
        '{}'
    """
    if mode not in ("wb", "w"):
        raise ValueError(f"mode: expected 'wb' or 'w', got {mode!r}")
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InputError(f"{path}: output folder {parent} does not exist")
    remove_stale(path)
    tmp = temp_path(path)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    try:
        kw = {"encoding": "utf-8", "newline": "\n"} if mode == "w" else {}
        with os.fdopen(fd, mode, **kw) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        # mkstemp creates 0600; give the file the permissions open() would have.
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException as e:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(e, OSError) and e.filename is None and e.errno:  # a full disk: say which file
            raise OSError(e.errno, e.strerror, str(path)) from None
        raise
    with contextlib.suppress(OSError):
        dfd = os.open(parent, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
