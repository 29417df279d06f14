"""``relightnet convert-checkpoint``: rewrite an older checkpoint in the safe (tensors and plain values) form."""

from __future__ import annotations

import argparse
import logging

from .options import add_command
from .paths import out_file

logger = logging.getLogger("relightnet.checkpoint")


def run(args: argparse.Namespace) -> int:
    from ..model.convert import convert_checkpoint

    out = convert_checkpoint(args.input, out_file(args.output, "NEW"))
    logger.info("wrote %s", out)
    return 0


def register(sub) -> None:
    p = add_command(
        sub,
        "convert-checkpoint",
        "Rewrite a checkpoint of your own made by older relightnet code (numpy values or config objects "
        "inside) as tensors and plain values, which every command loads without running pickle code. "
        "Only numpy arrays/scalars and relightnet's configs are accepted; anything else is refused by name.",
        "  relightnet convert-checkpoint runs/old/last.pt runs/old/last-safe.pt\n",
    )
    p.add_argument("input", metavar="OLD", help="the older checkpoint (.pt)")
    p.add_argument("output", metavar="NEW", help="where to write the converted checkpoint (may be OLD)")
    p.set_defaults(func=run)
