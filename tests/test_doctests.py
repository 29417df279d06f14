"""Every ``>>>`` example in the package's docstrings runs, and none drifts from what it shows.

The modules are the ones whose source holds an example; each runs with Python's doctest machinery
(ELLIPSIS and NORMALIZE_WHITESPACE on), in a temporary working folder; every such module must import
in the test environment (none needs bpy). :data:`MIN_EXAMPLES` keeps the set from
silently shrinking: it counts the docstrings with at least one example that ran (examples marked
``+SKIP`` do not run).
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


def _run(name: str) -> tuple[int, int, str]:
    """(failed, docstrings whose examples ran, report) of module ``name``."""
    module = importlib.import_module(name)
    out = io.StringIO()
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    failed = ran = 0
    for test in doctest.DocTestFinder(exclude_empty=True).find(module, name):
        result = runner.run(test, out=out.write)
        failed, ran = failed + result.failed, ran + (result.attempted > 0)
    return failed, ran, out.getvalue()


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """The run of every module's examples, once per test module: {module: (failed, docstrings, report)}."""
    import os

    done: dict[str, tuple[int, int, str]] = {}
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
    failed, _, report = results[name]
    assert failed == 0, report


def test_enough_examples_run(results):
    ran = sum(r[1] for r in results.values())
    assert ran >= MIN_EXAMPLES, f"the examples of {ran} docstrings ran, expected at least {MIN_EXAMPLES}"
