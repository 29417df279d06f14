"""Packages whose names load on first use: the same objects as eager imports, only what is used loaded."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest


@pytest.fixture
def package(tmp_path, monkeypatch):
    """A package ``lazypkg``: ``tool`` (a function in ``tool.py``, the module's own name) and ``Other``."""
    root = tmp_path / "lazypkg"
    root.mkdir()
    (root / "__init__.py").write_text(textwrap.dedent('''
        """A test package."""
        from relightnet.lazy import lazy_package
        _EXPORTS = {"tool": "tool", "Other": "other", "helper_fn": "other"}
        __all__ = lazy_package(__name__, _EXPORTS)
    '''))
    (root / "tool.py").write_text("def tool():\n    return 'tool'\n")
    (root / "helper_fn.py").write_text("VALUE = 1\n")
    (root / "other.py").write_text("from .helper_fn import VALUE\n\nclass Other:\n    v = VALUE\n\n"
                                   "def helper_fn():\n    return VALUE\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    yield "lazypkg"
    for name in [m for m in sys.modules if m == "lazypkg" or m.startswith("lazypkg.")]:
        del sys.modules[name]


def test_names_load_on_first_use(package):
    import lazypkg

    assert lazypkg.__all__ == ["tool", "Other", "helper_fn"]
    assert "lazypkg.other" not in sys.modules and "lazypkg.tool" not in sys.modules
    assert lazypkg.Other.v == 1 and "lazypkg.other" in sys.modules and "lazypkg.tool" not in sys.modules
    from lazypkg import tool

    assert tool() == "tool"
    assert {"tool", "Other", "helper_fn"} <= set(dir(lazypkg))
    with pytest.raises(AttributeError, match="no attribute 'missing'"):
        lazypkg.missing  # noqa: B018


def test_a_submodule_never_hides_the_export_of_its_name(package):
    import lazypkg.helper_fn
    import lazypkg.tool  # the import system binds each submodule to the package

    assert callable(lazypkg.tool) and lazypkg.tool() == "tool"
    assert lazypkg.helper_fn() == 1  # the function of other.py, not the module helper_fn.py
    assert sys.modules["lazypkg.tool"].tool is lazypkg.tool


@pytest.mark.slow
def test_relighting_a_photo_loads_neither_the_renderer_nor_the_ray_tracer():
    code = ("import sys, relightnet.pipeline.relight_image, relightnet.pipeline.backends; "
            "print(sorted(m for m in ('relightnet.prt', 'relightnet.render.jobs', 'relightnet.pipeline.avatar', "
            "'scipy.sparse', 'onnx') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert out.stdout.strip() == "[]"
