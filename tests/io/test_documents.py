"""YAML/JSON documents from strangers: aliases, nesting, size, special files, short quotes."""

from __future__ import annotations

import os

import pytest

from relightnet.checks import InputError
from relightnet.io.documents import MAX_DEPTH, clip, parse_document, read_document, short


def test_plain_documents_read(tmp_path):
    (tmp_path / "a.yaml").write_text("jobs:\n  - {command: x, args: [1, 2]}\n")
    assert read_document(tmp_path / "a.yaml", "jobs file") == {"jobs": [{"command": "x", "args": [1, 2]}]}
    (tmp_path / "a.json").write_text('{"sh": [[1, 2, 3]]}')
    assert read_document(tmp_path / "a.json", "light", yaml_ok=False) == {"sh": [[1, 2, 3]]}
    nested = "[" * MAX_DEPTH + "]" * MAX_DEPTH
    assert parse_document(nested, "x") == parse_document(nested, "x", yaml_ok=False)


@pytest.mark.parametrize("text, match", [
    ("a: &x [1, 2]\nb: *x\n", "anchors"),
    ("b: *x\n", "unreadable jobs file"),  # an alias to nothing
    ("jobs: " + "[" * 50_000 + "]" * 50_000, "nested deeper than 64"),
    ("jobs: " + "{a: " * 100 + "1" + "}" * 100, "nested deeper than 64"),
    ("x: !!python/object/apply:os.system [echo]\n", "unreadable jobs file"),
])
def test_hostile_yaml_is_refused_in_one_line(tmp_path, text, match):
    (tmp_path / "jobs.yaml").write_text(text)
    with pytest.raises(InputError, match=match) as e:
        read_document(tmp_path / "jobs.yaml", "jobs file")
    assert "\n" not in str(e.value) and len(str(e.value)) < 400 and "jobs.yaml" in str(e.value)


def test_hostile_json_is_refused(tmp_path):
    with pytest.raises(InputError, match="nested deeper"):
        parse_document('{"a": ' + "[" * 50_000 + "]" * 50_000 + "}", "f.json", yaml_ok=False)
    # brackets inside strings are not nesting
    assert parse_document('{"a": "' + "[" * 100 + '"}', "f.json", yaml_ok=False) == {"a": "[" * 100}
    with pytest.raises(InputError, match="f.json: unreadable"):
        parse_document("[" + "9" * 100_000 + "]", "f.json", yaml_ok=False)


def test_only_regular_files_of_bounded_size(tmp_path):
    fifo = tmp_path / "jobs.yaml"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match="not a regular file \\(a FIFO\\)"):
        read_document(fifo, "jobs file")  # returns at once: a FIFO is never opened
    with pytest.raises(InputError, match="folder"):
        read_document(tmp_path, "jobs file")
    with pytest.raises(InputError, match="missing.yaml: jobs file not found"):
        read_document(tmp_path / "missing.yaml", "jobs file")
    big = tmp_path / "big.yaml"
    with open(big, "wb") as f:
        f.truncate((16 << 20) + 1)
    with pytest.raises(InputError, match="at most"):
        read_document(big, "jobs file")


def test_short_quotes_are_bounded_whatever_the_value():
    v: list = ["lol"] * 9
    for _ in range(30):  # 9³⁰ strings through shared references
        v = [v] * 9
    assert len(short(v)) <= 100
    assert len(short("x" * 10**7)) <= 100
    assert short("abc") == "'abc'" and short(3) == "3"
    assert clip("a\nb  c") == "a b c" and len(clip("y" * 1000, 50)) == 50
