"""relightnet's exception classes, in a module that imports nothing (the command line reports
them without loading torch). :mod:`relightnet.checks` exports the same classes."""

__all__ = ["RelightError", "InputError", "ShapeError"]


class RelightError(Exception):
    """Base class of every error relightnet raises on bad input."""


class InputError(RelightError, ValueError):
    """A value is not acceptable: NaN, out of range, unreadable file, ..."""


class ShapeError(InputError):
    """A tensor or array has the wrong shape (a kind of bad input)."""
