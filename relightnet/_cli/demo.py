"""``relightnet demo``: run the most complete job on embedded defaults and say where to look."""

from __future__ import annotations

import argparse
import logging

from .common import add_command, pos_int

logger = logging.getLogger("relightnet.demo")


def run(args: argparse.Namespace) -> int:
    from ..pipeline.demo import run_demo

    if args.size % 16:
        raise ValueError(f"--size: expected a multiple of 16, got {args.size}")
    paths = run_demo(args.out, size=args.size, frames=args.frames, n_dirs=args.n_dirs)
    logger.info("demo written to %s:", args.out)
    logger.info("  light previews:        %s/lights/*.png (%d presets)", args.out, len(paths["lights"]))
    logger.info("  target photo:          %s", paths["target"])
    logger.info("  lights true|estimated: %s", paths["lights_true_vs_estimated"])
    logger.info("  avatar true|estimated: %s", paths["avatar_true_vs_estimated"])
    logger.info("  avatar walk (video):   %s", paths["walk"])
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "demo",
        "Run the demo on embedded defaults: preset light previews; estimate the light of a synthetic "
        "photo with the shipped CNN and relight the Anny avatar with it (PRT); a walking avatar clip.",
        "  relightnet demo\n  relightnet demo --out /tmp/demo --size 128 --frames 12\n",
    )
    p.add_argument("--out", default="out/demo", help="output folder (default: out/demo)")
    p.add_argument("--size", type=pos_int, default=256, help="image size, a multiple of 16 (default: 256)")
    p.add_argument("--frames", type=pos_int, default=48, help="frames of the walking clip (default: 48)")
    p.add_argument("--n-dirs", type=pos_int, default=64, help="PRT directions (default: 64)")
    p.set_defaults(func=run)
