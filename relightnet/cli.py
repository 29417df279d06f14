"""The ``relightnet`` command: parses arguments and calls library functions.

Each subcommand lives in ``relightnet/_cli/<name>.py`` and exposes
``register(subparsers)``, which adds its parser and sets ``func(args) -> int``.
Heavy imports happen inside ``func`` so ``relightnet --help`` stays fast.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

from . import __version__
from .checks import RelightError

logger = logging.getLogger("relightnet")

#: Subcommand modules under relightnet._cli, in --help order.
COMMAND_MODULES = [
    "light", "render", "synth", "model", "checkpoint", "smooth", "onnx", "relight", "avatar", "compare", "blender",
    "demo",
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="relightnet",
        description="Relight people in images and videos with spherical-harmonics light.",
        epilog="Run 'relightnet COMMAND --help' for a command's options and examples.",
    )
    parser.add_argument("--version", action="version", version=f"relightnet {__version__}")
    verbosity = parser.add_mutually_exclusive_group()
    verbosity.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    verbosity.add_argument("-q", "--quiet", action="store_true", help="log warnings and errors only")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f"relightnet._cli.{name}").register(sub)
    for command in _leaf_parsers(sub):  # every command reads files: one limit for all
        command.add_argument("--max-pixels", type=_max_pixels, metavar="N",
                             help="largest image or video frame decoded, width x height (default: 64000000, "
                                  "or $RELIGHTNET_MAX_PIXELS); larger files are refused before decoding")
    return parser


def _leaf_parsers(sub) -> list[argparse.ArgumentParser]:
    """The parsers of the commands under ``sub``, nested ones (``light show``) included."""
    out = []
    for p in sub.choices.values():
        nested = [a for a in p._actions if isinstance(a, argparse._SubParsersAction)]
        out += _leaf_parsers(nested[0]) if nested else [p]
    return out


def _max_pixels(text: str) -> int:
    try:
        v = int(float(text))
    except (ValueError, OverflowError):
        v = 0
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive number of pixels, got {text!r}")
    return v


def configure_logging(verbose: bool = False, quiet: bool = False) -> None:
    level = logging.DEBUG if verbose else logging.WARNING if quiet else logging.INFO
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", force=True)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args.verbose, args.quiet)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    if getattr(args, "max_pixels", None):
        from .io.limits import set_max_pixels

        set_max_pixels(args.max_pixels)
    try:
        return int(args.func(args) or 0)
    except (RelightError, FileNotFoundError, ValueError) as e:
        # One line naming the input and what was expected; no traceback.
        msg = f"{type(e).__name__}: {e}"
        sys.stderr.write(f"relightnet {args.command}: {msg}\n")
        return 1


if __name__ == "__main__":
    sys.exit(main())
