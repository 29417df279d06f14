"""The public surface: each subpackage's ``__all__`` exists, is documented, and is what other code imports."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import inspect
import pkgutil
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


#: The most public names the package may have in all (docs/design.md, "Layout").
MAX_PUBLIC_NAMES = 350


def _public_name_count() -> dict[str, int]:
    return {m.name: len(getattr(importlib.import_module(m.name), "__all__", []))
            for m in pkgutil.iter_modules([str(ROOT)], "relightnet.")}


def test_the_public_surface_stays_small():
    """The public names are the sum, over the modules ``relightnet.X`` (subpackages and top-level modules
    such as ``checks`` or ``names``, each found by ``pkgutil.iter_modules``), of ``len(relightnet.X.__all__)``:
    what a user of each floor needs. A helper used only by other floors of the package is imported from
    its defining module (``from ..sh.basis import sh_degrees``, listed in that module's ``__all__``) and
    does not count."""
    counts = _public_name_count()
    assert sum(counts.values()) <= MAX_PUBLIC_NAMES, sorted(counts.items(), key=lambda kv: -kv[1])


#: A dotted reference ``relightnet.X.Y...`` in prose: a module path or a module's attribute.
REFERENCE = re.compile(r"\brelightnet\.[a-z_]+(?:\.[A-Za-z_][A-Za-z0-9_]*)+")


def _resolves(ref: str) -> bool:
    """True when ``ref`` is a module, or a module's attribute (after the longest importable prefix)."""
    parts = ref.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for name in parts[i:]:
            if not hasattr(obj, name):
                return False
            obj = getattr(obj, name)
        return True
    return False


def test_the_reference_resolver():
    assert _resolves("relightnet.sh.basis.sh_count") and _resolves("relightnet.sh.basis")
    assert _resolves("relightnet.model.photo_albedo.ALBEDO_FLOOR")
    assert not _resolves("relightnet.sh.no_such_name") and not _resolves("relightnet.sh.basis.sh_count.x")


def test_every_reference_in_the_docs_and_docstrings_resolves():
    docs = [ROOT.parent / "README.md", *sorted((ROOT.parent / "docs").glob("*.md")), ROOT / "weights" / "MODEL_CARD.md"]
    bad = set()
    for f in [*docs, *sorted(ROOT.rglob("*.py"))]:
        for ref in REFERENCE.findall(f.read_text(encoding="utf-8")):
            if not _resolves(ref):
                bad.add((str(f.relative_to(ROOT.parent)), ref))
    assert not bad, sorted(bad)
