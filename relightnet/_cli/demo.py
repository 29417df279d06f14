"""``relightnet demo``: preview pictures of every preset light (until the full demo exists)."""

from __future__ import annotations

import argparse
import logging

from .common import add_command

logger = logging.getLogger("relightnet.demo")


def run(args: argparse.Namespace) -> int:
    from ..sh.visualize import render_presets

    paths = render_presets(args.out, size=args.size, lmax=args.lmax)
    logger.info("wrote %d preset previews to %s: %s", len(paths), args.out, ", ".join(p.name for p in paths))
    return 0


def register(sub) -> None:
    p = add_command(
        sub,
        "demo",
        "Write the demo pictures: a preview of every preset light (sphere front/back, SH lat-long, "
        "original environment map).",
        "  relightnet demo\n  relightnet demo --out /tmp/demo --size 128\n",
    )
    p.add_argument("--out", default="out/demo", help="output folder (default: out/demo)")
    p.add_argument("--size", type=int, default=256, help="sphere size in pixels (default: 256)")
    p.add_argument("--lmax", type=int, default=2, help="SH order of the preset lights (default: 2)")
    p.set_defaults(func=run)
