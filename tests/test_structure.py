"""The package's shape: small files and functions, no private name imported across subpackages, no
import cycle (module imports anywhere in a file count, lazy ones included)."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "relightnet"
MAX_FILE_LINES = 400
MAX_FUNCTION_LINES = 80


def _modules() -> dict[str, Path]:
    mods = {}
    for p in sorted(ROOT.rglob("*.py")):
        parts = list(p.relative_to(ROOT.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(parts)] = p
    return mods


MODULES = _modules()
TREES = {m: ast.parse(p.read_text(encoding="utf-8")) for m, p in MODULES.items()}


def _subpackage(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _imports(module: str):
    """(target module, imported name or None) of every relightnet import in ``module``."""
    is_pkg = MODULES[module].name == "__init__.py"
    package = module if is_pkg else module.rsplit(".", 1)[0]
    for node in ast.walk(TREES[module]):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target == "relightnet" or target.startswith("relightnet."):
                for alias in node.names:
                    yield target, alias.name
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("relightnet"):
                    yield alias.name, None


def test_no_file_over_the_limit():
    big = {m: p.read_text(encoding="utf-8").count("\n") for m, p in MODULES.items()}
    assert {m: n for m, n in big.items() if n > MAX_FILE_LINES} == {}


def test_no_function_over_the_limit():
    long = {}
    for m, tree in TREES.items():
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    long[f"{m}.{node.name}"] = n
    assert long == {}


def test_no_private_name_imported_across_subpackages():
    bad = []
    for m in MODULES:
        for target, name in _imports(m):
            full = f"{target}.{name}" if name else target
            dest = full if full in MODULES else target
            if _subpackage(dest) == _subpackage(m):
                continue
            private_name = name is not None and name.startswith("_") and not name.startswith("__")
            private_module = any(p.startswith("_") and not p.startswith("__") for p in dest.split(".")[1:])
            # the CLI's own helpers (relightnet._cli) are imported by relightnet.cli, its entry point
            if private_module and m == "relightnet.cli" and _subpackage(dest) == "_cli":
                continue
            if private_name or private_module:
                bad.append(f"{m} imports {full}")
    assert bad == []


def _graph() -> dict[str, set[str]]:
    edges: dict[str, set[str]] = {m: set() for m in MODULES}
    for m in MODULES:
        for target, name in _imports(m):
            full = f"{target}.{name}" if name else target
            dest = full if full in MODULES else target
            if dest in MODULES and dest != m:
                edges[m].add(dest)
    return edges


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in edges:
        if v not in index:
            visit(v)
    return out


def test_no_import_cycle():
    # A package's __init__ importing its own modules is not a cycle of the modules themselves.
    edges = {m: {d for d in ds if not (MODULES[d].name == "__init__.py" and m.startswith(d + "."))}
             for m, ds in _graph().items()}
    assert _cycles(edges) == []


@pytest.mark.parametrize("edges, expected", [
    ({"a": {"b"}, "b": {"a"}, "c": set()}, [["a", "b"]]),
    ({"a": {"b"}, "b": {"c"}, "c": set()}, []),
])
def test_the_cycle_finder_finds_cycles(edges, expected):
    assert _cycles(edges) == expected
