"""Every command line in the README (and train/, export/, docs/) is one the CLI accepts; the cheap ones run.

A command line is a line of a ```bash block that runs ``relightnet``, ``python -m train|export|relightnet``
or ``torchrun ... -m train|relightnet`` (a trailing backslash continues it, a ``#`` starts a comment).
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from relightnet.cli import build_parser, main
from relightnet.io import read_image
from relightnet.light import load_light

REPO = Path(__file__).resolve().parents[1]
DOCS = ["README.md", "train/README.md", "export/README.md", "docs/design.md", *sorted(
    str(p.relative_to(REPO)) for p in (REPO / "docs").glob("*.md") if p.name != "design.md")]


def _bash_lines(text: str) -> list[str]:
    lines, block, cont = [], False, ""
    for raw in text.splitlines():
        if raw.startswith("```"):
            block = raw.strip() == "```bash" if not block else False
            continue
        if not block:
            continue
        line = cont + raw.split(" #")[0].split("\t#")[0].rstrip()
        if line.endswith("\\"):
            cont = line[:-1] + " "
            continue
        cont = ""
        if line.strip() and not line.lstrip().startswith("#"):
            lines.append(line.strip())
    return lines


def relightnet_argv(line: str) -> list[str] | None:
    """The ``relightnet`` arguments a README line amounts to, or None for another program."""
    words = shlex.split(line)
    while words and re.fullmatch(r"[A-Z_]+=\S*", words[0]):  # OMP_NUM_THREADS=1 relightnet ...
        words = words[1:]
    if not words:
        return None
    if words[0] in ("relightnet", ".venv/bin/relightnet"):
        return words[1:]
    if "-m" in words and words[0] in ("python", "python3", "torchrun"):
        i = words.index("-m")
        module, rest = words[i + 1], words[i + 2:]
        if module == "relightnet":
            return rest
        if module == "train":
            return ["train", *rest]
        if module == "export":
            return ["onnx-run", *rest[1:]] if rest[:1] == ["serve"] else ["export", *rest]
    return None


COMMANDS = [(doc, line, argv) for doc in DOCS for line in _bash_lines((REPO / doc).read_text())
            if (argv := relightnet_argv(line)) is not None]


def test_the_documents_show_commands():
    docs = {doc for doc, _, _ in COMMANDS}
    assert {"README.md", "train/README.md", "export/README.md"} <= docs and len(COMMANDS) >= 40
    assert any(argv[:1] == ["train"] and "torchrun" in line for _, line, argv in COMMANDS)


@pytest.mark.parametrize("doc, line, argv", COMMANDS, ids=[f"{d}: {ln[:60]}" for d, ln, _ in COMMANDS])
def test_command_parses(doc, line, argv):
    if argv == ["--help"]:
        return  # relightnet --help: run below
    args = build_parser().parse_args(argv)  # a line the parser refuses exits 2 here, with its reason
    assert callable(args.func), f"{doc}: {line}: not a command"


#: Lines that need nothing but the package: run as written (in an empty folder).
CHEAP = [argv for _, _, argv in COMMANDS
         if argv[:2] in (["light", "show"], ["light", "convert"]) or argv == ["--help"]
         or argv[-1:] == ["--help"]]


@pytest.mark.parametrize("argv", CHEAP, ids=" ".join)
def test_cheap_commands_run_as_written(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    if argv[-1] == "--help":
        with pytest.raises(SystemExit) as e:
            main(argv)
        assert e.value.code == 0 and "usage: relightnet" in capsys.readouterr().out
        return
    inputs = {"studio.npz": "studio"}  # a README line reading a file an earlier line made
    for a in argv[2:]:
        if a in inputs and not Path(a).exists():
            assert main(["light", "convert", inputs[a], a]) == 0
    if any(a.endswith((".exr", ".npy")) and not Path(a).exists() and "/" in a for a in argv[2:3]):
        pytest.fail(f"{argv}: reads a file that a fresh clone does not have")
    assert main(["-q", *argv]) == 0
    out = Path(argv[-1] if argv[1] == "convert" else argv[argv.index("--out") + 1])
    if out.suffix == ".png":
        assert read_image(out).shape[0] > 0
    else:
        assert load_light(out).shape[-2:] == (9, 3)


def test_cheap_lines_are_found():
    assert ["--help"] in CHEAP and any(a[:2] == ["light", "show"] for a in CHEAP)
    assert sum(a[:2] == ["light", "convert"] for a in CHEAP) >= 2


def _python_blocks(text: str) -> list[str]:
    blocks, block = [], None
    for raw in text.splitlines():
        if block is None and raw.strip() == "```python":
            block = []
        elif block is not None and raw.startswith("```"):
            blocks.append("\n".join(block))
            block = None
        elif block is not None:
            block.append(raw)
    return blocks


def test_readme_python_runs(tmp_path, monkeypatch):
    """Each ```python block of the README runs as written, in a folder holding a small photo of a person."""
    import PIL.Image

    from relightnet.app.examples import example_person

    blocks = _python_blocks((REPO / "README.md").read_text())
    assert blocks, "the README shows no Python"
    PIL.Image.open(example_person(tmp_path / "example", res=128)).convert("RGB").save(tmp_path / "person.jpg")
    monkeypatch.chdir(tmp_path)
    for code in blocks:
        exec(compile(code, "README.md", "exec"), {"__name__": "readme"})
    if "relit.png" in "".join(blocks):
        assert read_image(tmp_path / "relit.png").shape == (128, 128, 3)
