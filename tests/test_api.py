"""The public surface: each subpackage's ``__all__`` exists, is documented, and is what other code imports."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import inspect
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "relightnet"
SUBPACKAGES = sorted(p.parent.name for p in ROOT.glob("*/__init__.py") if not p.parent.name.startswith("_"))


def _documented_constant(name: str, files) -> bool:
    """A module-level constant is documented by a ``#:`` comment above (or beside) its definition."""
    for f in files:
        lines = f.read_text().splitlines()
        for i, line in enumerate(lines):
            if re.match(rf"^{re.escape(name)}\s*(:[^=]*)?=", line):
                if "#:" in line:
                    return True
                j = i - 1
                while j >= 0 and lines[j].lstrip().startswith("#"):
                    if lines[j].lstrip().startswith("#:"):
                        return True
                    j -= 1
    return False


def test_every_subpackage_is_listed():
    assert {"sh", "raster", "body", "prt", "render", "model", "data", "temporal", "segment", "io", "pipeline",
            "distributed", "blender"} <= set(SUBPACKAGES)


@pytest.mark.parametrize("sub", SUBPACKAGES)
def test_all_names_exist_are_documented_and_complete(sub):
    pkg = importlib.import_module(f"relightnet.{sub}")
    names = pkg.__all__
    assert len(names) == len(set(names)), "a name listed twice"
    assert inspect.getdoc(pkg), "the subpackage has no docstring"
    files = [*sorted((ROOT / sub).glob("*.py")), ROOT / "names.py", ROOT / "checks.py"]
    for name in names:
        assert hasattr(pkg, name), f"relightnet.{sub}.{name} is listed in __all__ but does not exist"
        obj = getattr(pkg, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            doc = inspect.getdoc(obj) or ""
            assert doc and not doc.startswith(f"{obj.__name__}("), f"relightnet.{sub}.{name} has no docstring"
        else:
            assert _documented_constant(name, files), f"relightnet.{sub}.{name}: no '#:' comment where it is set"
    # nothing public missing: what a module defines with a docstring and the package imports is listed
    for name, obj in vars(pkg).items():
        if name.startswith("_") or inspect.ismodule(obj) or name == "annotations":
            continue
        if (inspect.isfunction(obj) or inspect.isclass(obj)) and obj.__module__.startswith(f"relightnet.{sub}"):
            assert name in names, f"relightnet.{sub} imports {name} but does not list it in __all__"


def _imported_names():
    """(file, module, name) of every relative import from another subpackage."""
    for f in sorted(ROOT.rglob("*.py")):
        rel = f.relative_to(ROOT)
        here = rel.parts[0] if len(rel.parts) > 1 else None
        for node in ast.walk(ast.parse(f.read_text())):
            if not (isinstance(node, ast.ImportFrom) and node.level >= 1):
                continue
            base = list(rel.parent.parts)
            target = base[: len(base) - (node.level - 1)] + (node.module.split(".") if node.module else [])
            if not target or target[0] == here:
                continue
            yield f, "relightnet." + ".".join(target), [a.name for a in node.names]


def test_no_private_or_unlisted_name_is_imported_across_subpackages():
    found = set()
    for f, module, imported in _imported_names():
        mod = importlib.import_module(module)
        listed = getattr(mod, "__all__", None)
        for name in imported:
            if hasattr(mod, "__path__") and importlib.util.find_spec(f"{module}.{name}") is not None:
                continue  # a submodule
            if name.startswith("_") or (listed is not None and name not in listed):
                found.add((str(f.relative_to(ROOT.parent)), module, name))
    assert not found, sorted(found)  # a name another subpackage uses is public
