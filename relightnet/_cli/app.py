"""``relightnet app``: the local web app (optional extra ``relightnet[app]``)."""

from __future__ import annotations

import argparse
import logging

from ..errors import InputError
from .options import add_command

logger = logging.getLogger("relightnet.app")


def _port(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        v = -1
    if not 0 <= v <= 65535:
        raise argparse.ArgumentTypeError(f"expected a TCP port 0-65535, got {text!r}")
    return v


def run(args: argparse.Namespace) -> int:
    try:
        import gradio  # noqa: F401
    except ImportError:
        raise InputError("the app needs Gradio: pip install 'relightnet[app]'") from None
    from ..app.server import launch

    launch(args.port)
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "app",
        "A local web app to relight a photo by hand: open a photo, see the person's mask, choose a light "
        "(direction on a sphere with strength, size, colour and ambient; a preset; an HDRI; a background plate) "
        "and see the relit photo update live; download it and the light; relight a video. Listens on 127.0.0.1 "
        "only; needs the extra relightnet[app] (Gradio).",
        "  relightnet app                 # http://127.0.0.1:7860\n"
        "  relightnet app --port 8080\n",
    )
    p.add_argument("--port", type=_port, default=7860, help="TCP port on 127.0.0.1 (default: %(default)s)")
    p.set_defaults(func=run)
