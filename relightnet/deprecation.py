"""The deprecation policy, as one helper (torch-free).

A public name, argument or spelling that changes is removed outright while the package is below
1.0 unless a caller outside it is known to depend on it; one that is kept goes through
:func:`deprecated`: it warns with a :class:`DeprecationWarning` that says since which version it
is deprecated, in which version it goes, and what to use instead, and it is removed in that
version (docs/design.md, "Deprecation").
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable

__all__ = ["deprecated", "warn_deprecated"]


def warn_deprecated(what: str, since: str, removal: str, replacement: str, stacklevel: int = 3) -> None:
    """Warn that ``what`` is deprecated: ``DeprecationWarning`` "WHAT is deprecated since relightnet
    SINCE and is removed in REMOVAL: use REPLACEMENT" (pointing at the caller's caller by default)."""
    warnings.warn(f"{what} is deprecated since relightnet {since} and is removed in {removal}: use {replacement}",
                  DeprecationWarning, stacklevel=stacklevel)


def deprecated(since: str, removal: str, replacement: str) -> Callable:
    """Decorate a function kept for old callers: each call warns (:func:`warn_deprecated`), naming
    the function, then runs it."""

    def wrap(func: Callable) -> Callable:
        @functools.wraps(func)
        def call(*args, **kwargs):
            warn_deprecated(f"{func.__module__}.{func.__qualname__}", since, removal, replacement)
            return func(*args, **kwargs)

        call.__doc__ = f"Deprecated since {since}, removed in {removal}: use {replacement}. {func.__doc__ or ''}"
        return call

    return wrap
