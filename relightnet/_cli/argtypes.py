"""Argument types of the command line: argparse ``type=`` callables that refuse bad text with a
usage error naming what was expected (torch-free, so ``--help`` stays instant)."""

from __future__ import annotations

import argparse

__all__ = ["exposure_arg", "nonneg_int", "pos_int", "pos_float", "quality", "work_size", "image_size", "key_value_arg",
           "phenotype_arg"]


def _parsed(text: str, cast, ok, expected: str):
    """``cast(text)`` when it parses and ``ok`` accepts it, else a usage error "expected EXPECTED, got TEXT"."""
    try:
        v = cast(text)
    except (ValueError, OverflowError):
        v = None
    if v is None or not ok(v):
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
    return v


def exposure_arg(text: str):
    """'auto' or a number > 0 (an exposure)."""
    return text if text == "auto" else _parsed(text, float, lambda v: v > 0, "'auto' or a positive number")


def nonneg_int(text: str) -> int:
    """An integer >= 0."""
    return _parsed(text, int, lambda v: v >= 0, "a non-negative integer")


def pos_int(text: str) -> int:
    """An integer >= 1."""
    return _parsed(text, int, lambda v: v >= 1, "a positive integer")


def pos_float(text: str) -> float:
    """A finite number > 0."""
    return _parsed(text, float, lambda v: 0 < v < float("inf"), "a positive number")


def quality(text: str) -> int:
    """A JPEG/WebP quality: an integer from 1 to 100."""
    return _parsed(text, int, lambda v: 1 <= v <= 100, "an integer from 1 to 100")


def _int_in(text: str, lo: int, hi: int, step: int, expected: str) -> int:
    """An integer in [lo, hi] that is a multiple of ``step``, else an argparse error saying ``expected``."""
    return _parsed(text, int, lambda v: lo <= v <= hi and v % step == 0, expected)


def work_size(text: str) -> int:
    """The CNN's working size: a positive multiple of 16, at most 2048."""
    return _int_in(text, 16, 2048, 16, "a multiple of 16 from 16 to 2048")


def image_size(text: str) -> int:
    """A picture's size in pixels: 1 to 4096."""
    return _int_in(text, 1, 4096, 1, "a size from 1 to 4096 pixels")


def key_value_arg(keys, cast, key_name: str = "NAME", value_name: str = "a number"):
    """An argparse type parsing ``KEY=VALUE`` with KEY in ``keys`` (a sequence or a callable giving one)."""

    def parse(text: str):
        names = keys() if callable(keys) else keys
        k, sep, v = text.partition("=")
        if not sep or k not in names:
            raise argparse.ArgumentTypeError(
                f"expected {key_name}=VALUE with {key_name} in {', '.join(names)}, got {text!r}"
            )
        try:
            return k, cast(v)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {value_name} after '{k}=', got {v!r}") from None

    return parse


def _phenotypes():
    from ..body import PHENOTYPES

    return PHENOTYPES


#: ``--phenotype NAME=VALUE`` for Anny (names from relightnet.body.PHENOTYPES).
phenotype_arg = key_value_arg(_phenotypes, float, "NAME", "a number")
