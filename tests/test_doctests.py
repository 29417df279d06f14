"""Every ``>>>`` example in the package's docstrings runs, and none drifts from what it shows.

The modules are the ones whose source holds an example; each runs with Python's doctest machinery
(ELLIPSIS and NORMALIZE_WHITESPACE on), in a temporary working folder. A module whose optional
package is missing (bpy, gradio) is skipped, not failed. :data:`MIN_EXAMPLES` keeps the set from
silently shrinking: examples marked ``+SKIP`` do not count.
"""

from __future__ import annotations

import doctest
import importlib
import io
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "relightnet"
MIN_EXAMPLES = 25
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = sorted(_module_name(p) for p in ROOT.rglob("*.py") if ">>>" in p.read_text(encoding="utf-8"))


def _run(name: str) -> tuple[int, int, str] | None:
    """(failed, attempted, report) of the examples in module ``name``; None when an optional package
    it imports is missing."""
    try:
        module = importlib.import_module(name)
    except ModuleNotFoundError as e:
        if e.name and not e.name.startswith("relightnet"):
            return None
        raise
    out = io.StringIO()
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    for test in doctest.DocTestFinder(exclude_empty=True).find(module, name):
        if test.examples:
            runner.run(test, out=out.write)
    failed, attempted = runner.summarize(verbose=False)
    return failed, attempted, out.getvalue()


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """The run of every module's examples, once per test module: {module: (failed, attempted, report)}."""
    import os

    done: dict[str, tuple[int, int, str] | None] = {}
    here = os.getcwd()
    os.chdir(tmp_path_factory.mktemp("doctests"))
    try:
        for name in MODULES:
            done[name] = _run(name)
    finally:
        os.chdir(here)
    return done


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(results, name):
    if results[name] is None:
        pytest.skip(f"{name}: an optional package is missing")
    failed, _, report = results[name]
    assert failed == 0, report


def test_enough_examples_run(results):
    attempted = sum(r[1] for r in results.values() if r is not None)
    assert attempted >= MIN_EXAMPLES, f"{attempted} doctest examples ran, expected at least {MIN_EXAMPLES}"
