"""The ``relightnet`` command: parses arguments and calls library functions.

Each subcommand lives in ``relightnet/_cli/<name>.py`` and exposes
``register(subparsers)``, which adds its parser and sets ``func(args) -> int``.
Heavy imports (torch and everything built on it) happen inside ``func``, never at
import or registration time, so every ``--help`` answers without importing torch;
the names listed in the help come from :mod:`relightnet.names`.

The rules every command follows (see ``docs/design.md``, "Command line"):

- Output paths are checked, and their missing parent folders made, before any work
  (:func:`relightnet._cli.paths.out_file` / :func:`~relightnet._cli.paths.out_dir`).
- Bad input ends in one line on stderr, ``relightnet COMMAND: ...``, and exit status 1;
  Ctrl-C in one line (with the command's resume hint, if it has one) and status 130.
- Only relightnet's own loggers speak at INFO; third-party libraries at WARNING (all at
  ``-v``).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Iterator

from . import __version__

logger = logging.getLogger("relightnet")

#: Subcommand modules under relightnet._cli, in --help order.
COMMAND_MODULES = [
    "light", "render", "synth", "model", "checkpoint", "smooth", "onnx", "segment", "fit", "capture", "relight",
    "avatar", "compare", "blender", "demo", "batch", "app",
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
    from .io.limits import DEFAULT_MAX_PIXELS  # torch-free

    for command in _leaf_parsers(sub):  # every command reads files: one limit for all
        command.add_argument("--max-pixels", type=_max_pixels, metavar="N",
                             help="largest image or video frame, width x height: a file whose header gives more "
                                  "is refused before a pixel is decoded, and the decoder refuses a frame whose "
                                  "size only it knows at 1/16 more (it counts the sides padded for alignment) "
                                  f"(default: {DEFAULT_MAX_PIXELS:,}, or $RELIGHTNET_MAX_PIXELS when set)")
    return parser


def command_table(parser: argparse.ArgumentParser | None = None) -> dict[str, argparse.ArgumentParser]:
    """The commands of ``parser`` (default: :func:`build_parser`'s) and their parsers, in --help order."""
    for action in (parser or build_parser())._actions:  # argparse keeps subparsers here, with no public accessor
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


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


class _OwnMessages(logging.Filter):
    """Passes relightnet's messages and every library's warnings and errors."""

    def filter(self, record: logging.LogRecord) -> bool:
        return record.levelno >= logging.WARNING or record.name == "relightnet" or record.name.startswith("relightnet.")


def configure_logging(verbose: bool = False, quiet: bool = False) -> None:
    """Log to stderr: relightnet's messages from INFO (DEBUG with ``verbose``, WARNING with ``quiet``);
    third-party libraries (ONNX Runtime's quantiser, Ray, ...) only from WARNING unless ``verbose``."""
    level = logging.DEBUG if verbose else logging.WARNING if quiet else logging.INFO
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", force=True)
    if not verbose:
        for handler in logging.getLogger().handlers:
            handler.addFilter(_OwnMessages())


def error_line(e: BaseException) -> str | None:
    """The one-line message of an error caused by the user's input, or None for a bug.

    Input errors are relightnet's :class:`~relightnet.errors.RelightError`, ``ValueError``
    and ``OSError`` (a missing file or folder, no permission, a full disk).
    """
    from .errors import RelightError

    if isinstance(e, OSError) and e.filename is not None and not isinstance(e, RelightError):
        text = f"{e.filename}: {(e.strerror or str(e)).lower()}"
    elif isinstance(e, (RelightError, OSError, ValueError)):
        text = str(e) or type(e).__name__
    else:
        return None
    first = text.strip().splitlines()[0] if text.strip() else type(e).__name__
    return f"{type(e).__name__}: {first}"


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like Ctrl-C, so a terminated command cleans up as an interrupted one."""


@contextlib.contextmanager
def _terminate_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` (where its handler is the default, in the
    main thread): the temporary files and new folders of the command are removed on the way out."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        yield
        return

    def stop(signum, frame):
        raise Terminated()

    signal.signal(signal.SIGTERM, stop)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def keep_temp_folder_clean() -> None:
    """Before onnxruntime or torch is imported: ONNX Runtime's telemetry off (it leaves a ``.ses``
    file in the temp folder) and torch's kernel cache (``import torch._dynamo`` makes
    ``torchinductor_<user>/`` there) in the user's cache folder; values the user set are kept."""
    os.environ.setdefault("ORT_DISABLE_TELEMETRY", "1")
    cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    os.environ.setdefault("TORCHINDUCTOR_CACHE_DIR", os.path.join(cache, "relightnet", "torchinductor"))


def main(argv: list[str] | None = None) -> int:
    """Run ``relightnet`` with ``argv`` (default: ``sys.argv[1:]``); returns the exit status."""
    keep_temp_folder_clean()
    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args.verbose, args.quiet)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    if getattr(args, "max_pixels", None):
        from .io.limits import set_max_pixels

        set_max_pixels(args.max_pixels)
    from ._cli.paths import made_folders

    try:
        with made_folders(), _terminate_as_interrupt():  # a failed command removes the folders it made
            return int(args.func(args) or 0)
    except Terminated:
        sys.stderr.write(f"relightnet {args.command}: terminated\n")
        return 128 + signal.SIGTERM
    except KeyboardInterrupt:
        hint = getattr(args, "interrupt_hint", None)
        sys.stderr.write(f"relightnet {args.command}: interrupted{'; ' + hint(args) if hint else ''}\n")
        return 130
    except Exception as e:  # input errors become one line; anything else is a bug and keeps its traceback
        line = error_line(e)
        if line is None:
            raise
        sys.stderr.write(f"relightnet {args.command}: {line}\n")
        return 1


if __name__ == "__main__":
    sys.exit(main())
