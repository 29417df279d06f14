"""Package namespaces that load their modules on first use (PEP 562), torch-free.

A subpackage whose ``__init__.py`` would import every module (the renderer, the ray tracer, the
jobs) makes any one command pay for all of them at start-up. :func:`lazy_package` lets the
``__init__`` list its public names instead: ``relightnet.pipeline.relight_image`` then imports only
what relighting a photo needs, while ``from relightnet.pipeline import avatar`` still works and
gives the same object as before.
"""

from __future__ import annotations

import importlib
import sys
import types
from collections.abc import Mapping

__all__ = ["lazy_package"]


class _LazyPackage(types.ModuleType):
    """A package module whose public names load on first access.

    A public name that is also a submodule's name (the function ``pipeline.avatar`` defined in
    ``pipeline/avatar.py``) stays the public object when that submodule is imported: the import
    system binds a submodule to the package's attribute, and this class leaves such a binding out,
    so the name resolves to its export as an eager ``from .avatar import avatar`` made it."""

    _exports: Mapping[str, str]

    def __getattr__(self, name: str):
        module = self._exports.get(name)
        if module is None:
            raise AttributeError(f"module {self.__name__!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{self.__name__}.{module}"), name)
        super().__setattr__(name, value)
        return value

    def __dir__(self) -> list[str]:
        return sorted(set(self.__dict__) | set(self._exports))

    def __setattr__(self, name: str, value) -> None:
        if isinstance(value, types.ModuleType) and name in self._exports:
            return
        super().__setattr__(name, value)


def lazy_package(name: str, exports: Mapping[str, str]) -> list[str]:
    """Make the package ``name`` (its ``__name__``) load each public name from its module on first use.

    Args:
        name: the package's ``__name__``; the package must already be in ``sys.modules`` (call this
            from its ``__init__.py``).
        exports: public name → the module of this package (relative, no dots) that defines it.

    Returns:
        The public names, in order: the package's ``__all__``.
    """
    module = sys.modules[name]
    module.__dict__["_exports"] = dict(exports)
    module.__class__ = _LazyPackage
    return list(exports)
