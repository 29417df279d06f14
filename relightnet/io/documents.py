"""YAML and JSON documents from strangers, read with bounded memory and time.

Configs, jobs files and light ``.json`` files are small documents; a stranger's can still
ask for a lot: YAML anchors and aliases expand exponentially when a value is walked or
printed ("billion laughs"), nesting 50,000 levels deep ends Python's recursion, and a
multi-megabyte value quoted in an error message floods the terminal. The readers here:

- open only regular files of at most :data:`MAX_DOCUMENT_BYTES` (no FIFO, device, folder);
- refuse YAML anchors and aliases and any YAML tag that builds a Python object
  (``yaml.SafeLoader`` underneath);
- refuse nesting deeper than :data:`MAX_DEPTH`, YAML and JSON alike, before Python recurses;

and :func:`short` is the one way an error message quotes a value from a file (at most
~100 characters, whatever the value holds).
"""

from __future__ import annotations

import dataclasses
import json
import os
import reprlib
import stat
from pathlib import Path

from ..errors import InputError

__all__ = ["MAX_DOCUMENT_BYTES", "MAX_DEPTH", "read_document", "parse_document", "short", "clip", "check_regular_file",
           "from_mapping"]

#: Largest YAML/JSON document read (bytes).
MAX_DOCUMENT_BYTES = 16 << 20
#: Deepest nesting of mappings and lists accepted.
MAX_DEPTH = 64
_SHORT = 100

_repr = reprlib.Repr()
_repr.maxlevel, _repr.maxdict, _repr.maxlist, _repr.maxtuple, _repr.maxset = 3, 6, 6, 6, 6
_repr.maxstring, _repr.maxother, _repr.maxlong = 80, 80, 40


def short(value, limit: int = _SHORT) -> str:
    """``repr(value)`` cut to about ``limit`` characters; linear in ``limit``, not in the value.

    Shared or deeply nested values (a YAML or pickle "laugh") cost no more than flat ones:
    the repr stops at a few levels and a few items per container.
    """
    try:
        text = _repr.repr(value)
    except Exception:  # noqa: BLE001 - a value whose repr fails is shown by its type
        text = f"<{type(value).__name__}>"
    text = text.replace("\n", "\\n")
    return text if len(text) <= limit else text[: limit - 3] + "..."


def clip(text: str, limit: int = _SHORT) -> str:
    """A message's text on one line, cut to ``limit`` characters (e.g. a parser's complaint)."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def check_regular_file(path: str | os.PathLike, what: str) -> int:
    """Refuse a missing path or one that is not a regular file (a FIFO, a device, a folder).

    Returns:
        The file's size in bytes.

    Raises:
        InputError: ``"jobs.yaml: not a regular file (a FIFO); expected a jobs file"``.
    """
    try:
        st = os.stat(path)
    except OSError:
        raise InputError(f"{path}: {what} not found") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a folder" if stat.S_ISDIR(st.st_mode) else "a FIFO" if stat.S_ISFIFO(st.st_mode) else "a special file"
        raise InputError(f"{path}: not a regular file ({kind}); expected a {what}")
    return st.st_size


def _loader():
    import yaml

    class _Loader(yaml.SafeLoader):
        """``SafeLoader`` that refuses anchors/aliases and counts nesting while composing."""

        _depth = 0

        def compose_node(self, parent, index):
            if self.check_event(yaml.AliasEvent):
                raise yaml.YAMLError("YAML aliases (*name) are not accepted")
            event = self.peek_event()
            if getattr(event, "anchor", None) is not None:
                raise yaml.YAMLError("YAML anchors (&name) are not accepted")
            self._depth += 1
            try:
                if self._depth > MAX_DEPTH:
                    raise yaml.YAMLError(f"nested deeper than {MAX_DEPTH} levels")
                return super().compose_node(parent, index)
            finally:
                self._depth -= 1

    return _Loader


def _json_depth_ok(text: str) -> bool:
    """Whether brackets outside strings nest at most :data:`MAX_DEPTH` deep (one linear scan)."""
    depth, in_str, escape = 0, False, False
    for ch in text:
        if in_str:
            if escape:
                escape = False
            elif ch == "\\":
                escape = True
            elif ch == '"':
                in_str = False
        elif ch == '"':
            in_str = True
        elif ch in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                return False
        elif ch in "]}":
            depth -= 1
    return True


def parse_document(text: str, where: str, what: str = "document", yaml_ok: bool = True):
    """Parse YAML (a superset of JSON) or, with ``yaml_ok=False``, strict JSON; bounded as above.

    Args:
        where: the file (or other source) named in messages; what: what it is ("jobs file").

    Raises:
        InputError: ``"{where}: unreadable {what} (YAML ...)"``, one line.
    """
    if len(text) > MAX_DOCUMENT_BYTES:
        raise InputError(f"{where}: {len(text)} characters; a {what} of at most {MAX_DOCUMENT_BYTES} is read")
    if not yaml_ok:
        if not _json_depth_ok(text):
            raise InputError(f"{where}: unreadable {what} (JSON nested deeper than {MAX_DEPTH} levels)")
        try:
            return json.loads(text)
        except (ValueError, RecursionError) as e:  # also numbers over Python's digit limit
            raise InputError(f"{where}: unreadable {what} (JSON {type(e).__name__}: {clip(str(e), 160)})") from None
    import yaml

    try:
        return yaml.load(text, Loader=_loader())  # noqa: S506 - a SafeLoader subclass
    except (yaml.YAMLError, ValueError, TypeError, OverflowError, RecursionError) as e:
        raise InputError(f"{where}: unreadable {what} (YAML {type(e).__name__}: {clip(str(e), 160)})") from None


def read_document(path: str | os.PathLike, what: str, yaml_ok: bool = True):
    """Read a YAML/JSON document from a regular file of at most :data:`MAX_DOCUMENT_BYTES`.

    Args:
        path: the file.
        what: what the file is, for messages ("jobs file", "config").
        yaml_ok: parse YAML (JSON is YAML); False: strict JSON.

    Raises:
        InputError: missing or special file, too large, not UTF-8, unreadable, aliases, too deep.
    """
    size = check_regular_file(path, what)
    if size > MAX_DOCUMENT_BYTES:
        raise InputError(f"{path}: {size} bytes; a {what} of at most {MAX_DOCUMENT_BYTES} bytes is read")
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_DOCUMENT_BYTES + 1)
        text = data.decode("utf-8")
    except OSError as e:
        raise InputError(f"{path}: cannot read the {what} ({e.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: the {what} is not UTF-8 text") from None
    return parse_document(text, f"{Path(path)}", what, yaml_ok=yaml_ok)


def from_mapping(cls, value, where: str):
    """A dataclass ``cls`` from a document's mapping (a config or one of its sections), its keys checked.

    Args:
        cls: the dataclass; its ``__init__`` checks the values.
        value: a mapping of ``cls``'s field names (or already a ``cls``, returned as it is).
        where: what the user calls the mapping; starts the error message.

    Raises:
        InputError: ``value`` is not a mapping, or has keys that are not fields of ``cls``.
    """
    if isinstance(value, cls):
        return value
    if not isinstance(value, dict):
        raise InputError(f"{where}: expected a mapping, got {type(value).__name__}")
    unknown = set(value) - {f.name for f in dataclasses.fields(cls)}
    if unknown:
        raise InputError(f"{where}: unknown keys {short(sorted(map(str, unknown)))}")
    return cls(**value)
