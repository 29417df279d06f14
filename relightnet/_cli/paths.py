"""The output-path rule of every command and the check of input paths, applied before any work.

An output file's type is checked and the missing parent folders of every output are made
first; :func:`made_folders` (around one command, in :func:`relightnet.cli.main`) removes the
folders the rule made if the command fails and they are still empty. The folders made are kept
per command run (a context variable set by :func:`made_folders`), not in module state.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from ..errors import InputError

__all__ = ["in_path", "out_file", "out_dir", "made_folders"]

#: The folders the output rule made during the running command (None outside :func:`made_folders`).
_RUN: contextvars.ContextVar[list[Path] | None] = contextvars.ContextVar("relightnet_made_folders", default=None)


@contextlib.contextmanager
def made_folders() -> Iterator[list[Path]]:
    """Run one command: the folders :func:`out_file` / :func:`out_dir` make inside the block are
    listed, and removed (those still empty, deepest first) when the block raises."""
    made: list[Path] = []
    token = _RUN.set(made)
    try:
        yield made
    except BaseException:
        for folder in reversed(made):
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise
    finally:
        _RUN.reset(token)


def _check_writable_parent(path: Path, option: str) -> None:
    """Make the missing parent folders of ``path``; an InputError naming ``option`` if that fails."""
    parent = path.parent
    missing = []
    q = parent
    while not q.exists() and q != q.parent:
        missing.append(q)
        q = q.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"{option} {path}: cannot make its folder {parent} ({e.strerror or e})") from None
    run = _RUN.get()
    if run is not None:
        run.extend(reversed(missing))
    _probe_writable(parent, path, option)


def _probe_writable(folder: Path, path: Path, option: str) -> None:
    """Create and remove a file in ``folder`` (permission bits alone do not tell: root, read-only
    mounts, immutable folders); an InputError naming ``option`` if that fails."""
    try:
        fd, probe = tempfile.mkstemp(prefix=".relightnet-probe-", dir=folder)
    except OSError as e:
        raise InputError(f"{option} {path}: the folder {folder} is not writable "
                         f"({(e.strerror or str(e)).lower()})") from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(probe)


def in_path(path: str | Path, option: str, expected: str = "an existing file or folder") -> Path:
    """An input path that must exist, checked before any work.

    Raises:
        InputError: ``option PATH: not found (expected ...)``.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"{option} {p}: not found (expected {expected})")
    return p


def _same_file(a: Path, b: Path) -> bool:
    """True when two paths name one file (the same path, a link to it, or a hard link)."""
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet)
        return a.resolve() == b.resolve()


def out_file(path: str | Path, option: str = "--out", suffixes: tuple[str, ...] | None = None,
             inputs: Iterable[str | Path | None] = ()) -> Path:
    """The output-file rule of every command, applied before any work.

    The file's type must be one of ``suffixes`` (case-insensitive; any if None), the path must
    not be an existing folder nor one of the command's ``inputs`` (an original is never
    overwritten by its result), and its missing parent folders are made. The file itself is
    written later, atomically, by the command.

    Args:
        path: the output file.
        option: the option that named it, for messages.
        suffixes: the file types allowed (lower case, with the dot); None: any.
        inputs: the command's input paths (None entries ignored).

    Returns:
        ``path`` as a Path.

    Raises:
        InputError: a wrong suffix, a folder at ``path``, an input at ``path``, or a parent
        folder that cannot be made.
    """
    p = Path(path)
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise InputError(f"{option} {p}: expected a file ending in {', '.join(suffixes)}")
    if p.is_dir():
        raise InputError(f"{option} {p}: is a folder; expected a file path")
    for src in inputs:
        if src is not None and Path(src).is_file() and _same_file(p, Path(src)):
            raise InputError(f"{option} {p}: is the input {src}; write the result to another file")
    _check_writable_parent(p, option)
    return p


def out_dir(path: str | Path, option: str = "--out") -> Path:
    """The output-folder rule of every command, applied before any work.

    The path must not be an existing file; its missing parent folders are made (the folder
    itself is made by the command when it writes, so a run that fails early leaves none).

    Raises:
        InputError: a file at ``path``, or a parent folder that cannot be made.
    """
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise InputError(f"{option} {p}: is a file; expected a folder (made if needed)")
    _check_writable_parent(p, option)
    if p.is_dir():
        _probe_writable(p, p, option)
    return p
