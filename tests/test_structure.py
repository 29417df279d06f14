"""The package's shape: small files and functions, no private name imported across subpackages, every
import going down the declared floors (:data:`FLOORS`, as in docs/design.md "Layers"), no import cycle
between packages or modules (module imports anywhere in a file count, lazy ones included)."""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "relightnet"
MAX_FILE_LINES = 400
MAX_FUNCTION_LINES = 80
MAX_PARAMETERS = 12  # options that travel together go as one frozen settings object (docs/design.md)

#: The floors of the package, bottom first (docs/design.md, "Layers"). A module may import its own
#: subpackage and anything on a lower floor, never the same floor's other packages or a higher one;
#: imports inside functions count. "" is ``relightnet/__init__.py`` (only ``__version__``); the other
#: names are subpackages (``relightnet/NAME/``) or top-level modules (``relightnet/NAME.py``).
FLOORS: tuple[tuple[str, ...], ...] = (
    ("", "errors"),
    ("checks", "color", "deprecation", "lazy", "names", "threads"),
    ("io",),
    ("raster",),
    ("sh",),
    ("light",),
    ("body",),
    ("segment",),
    ("distributed",),
    ("fit",),
    ("prt",),
    ("temporal",),
    ("render",),
    ("data",),
    ("blender", "capture"),
    ("model",),
    ("pipeline",),
    ("app",),
    ("_cli",),
    ("cli",),
    ("__main__",),
)
FLOOR = {name: i for i, floor in enumerate(FLOORS) for name in floor}


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


def _parameter_count(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Positional, keyword-only, ``*args`` and ``**kwargs`` parameters, ``self``/``cls`` not counted."""
    a = node.args
    names = [x.arg for x in (*a.posonlyargs, *a.args, *a.kwonlyargs)]
    return sum(n not in ("self", "cls") for n in names) + (a.vararg is not None) + (a.kwarg is not None)


def test_no_function_takes_too_many_parameters():
    many = {}
    for m, tree in TREES.items():
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and _parameter_count(node) > MAX_PARAMETERS:
                many[f"{m}.{node.name}"] = _parameter_count(node)
    assert many == {}


def test_the_parameter_count_counts_every_kind():
    f = ast.parse("def f(self, a, /, b, *c, d, **e): pass").body[0]
    assert _parameter_count(f) == 5


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


def _package_edges() -> set[tuple[str, str, str]]:
    """(importing module, imported module, ...) as (module, dest, dest's package) for every import
    that leaves the importing module's package."""
    out = set()
    for m in MODULES:
        for target, name in _imports(m):
            full = f"{target}.{name}" if name else target
            dest = full if full in MODULES else target
            if _subpackage(dest) != _subpackage(m):
                out.add((m, dest, _subpackage(dest)))
    return out


def _climbs(edges, floor: dict[str, int]) -> list[str]:
    """Imports ``(module, dest)`` whose package is not on a lower floor than the importer's."""
    bad = []
    for m, dest in sorted(edges):
        a, b = _subpackage(m), _subpackage(dest)
        if a != b and floor[b] >= floor[a]:
            bad.append(f"{m} (floor {floor[a]}: {a or 'relightnet'}) imports {dest} (floor {floor[b]}: "
                       f"{b or 'relightnet'})")
    return bad


def test_every_package_has_a_floor():
    assert sorted({_subpackage(m) for m in MODULES} - set(FLOOR)) == []
    assert len(FLOOR) == sum(len(f) for f in FLOORS)  # each name on one floor


def test_the_design_doc_lists_the_same_floors():
    text = (ROOT.parent / "docs" / "design.md").read_text(encoding="utf-8")
    section = text.split("## Layers", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| (\d+) \| (.+) \|$", section, flags=re.M)
    doc = [tuple(sorted("" if n == "relightnet/__init__.py" else n for n in re.findall(r"`([^`]+)`", names)
                        if n in FLOOR or n == "relightnet/__init__.py"))
           for _, names in rows]
    assert [int(i) for i, _ in rows] == list(range(len(FLOORS)))
    assert doc == [tuple(sorted(f)) for f in FLOORS]


def test_imports_only_go_down_the_floors():
    assert _climbs({(m, d) for m, d, _ in _package_edges()}, FLOOR) == []


def test_no_package_cycle():
    edges: dict[str, set[str]] = {_subpackage(m): set() for m in MODULES}
    for m, _, pkg in _package_edges():
        edges[_subpackage(m)].add(pkg)
    assert _cycles(edges) == []


def test_the_floor_check_finds_climbs():
    floor = {"": 0, "io": 1, "model": 2, "pipeline": 3}
    edges = {("relightnet.model.a", "relightnet.pipeline.b"), ("relightnet.pipeline.b", "relightnet.io.c"),
             ("relightnet.model.a", "relightnet.model.d"), ("relightnet.io.c", "relightnet")}
    assert _climbs(edges, floor) == ["relightnet.model.a (floor 2: model) imports relightnet.pipeline.b (floor 3: "
                                     "pipeline)"]
    assert _climbs({("relightnet.io.c", "relightnet.io.e"), ("relightnet.io.c", "relightnet.x")},
                   {"": 0, "io": 1, "x": 1}) == ["relightnet.io.c (floor 1: io) imports relightnet.x (floor 1: x)"]


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
