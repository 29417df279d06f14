"""``relightnet demo``: run the whole job on embedded defaults and say where to look."""

from __future__ import annotations

import argparse

from ..errors import InputError
from .argtypes import pos_int
from .options import add_command
from .paths import out_dir


def run(args: argparse.Namespace) -> int:
    from ..pipeline.demo import run_demo

    for name in ("size", "compare_size"):
        if getattr(args, name) % 16:
            raise InputError(f"--{name.replace('_', '-')}: expected a multiple of 16, got {getattr(args, name)}")
    p = run_demo(out_dir(args.out), size=args.size, frames=args.frames, n_dirs=args.n_dirs,
                 compare_clips=args.compare_clips, compare_size=args.compare_size, compare_frames=args.compare_frames,
                 progress=not args.quiet)
    out = args.out
    lines = [
        f"demo written to {out}/ — where to look:",
        f"  target clip (person under a turning light): {p['target']}",
        f"  avatar lit by the target's estimated light:  {p['avatar']}",
        f"  target | avatar, side by side:               {p['side_by_side']}",
        f"  light curves raw/smoothed/true:              {p['lights_plot']}",
        f"  dressed avatar in place of a walking person: {p['replace_avatar']} (plate: {p['replace_plate']})",
        f"  motion transfer, source | avatar:            {p['motion_side_by_side']}",
        f"  capture, source | captured person | truth:   {p['capture_side_by_side']}",
        f"  2D vs 3D vs ground truth report:             {p['compare']}/report.md",
        f"  preset light previews:                       {out}/lights/*.png",
    ]
    if not args.quiet:
        print("\n".join(lines))  # the command's own output (stdout), not a log message
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "demo",
        "Run the whole job on embedded defaults (shipped CNN, Anny, shipped env maps): make a target clip of a "
        "person walking under a changing light, put the Anny avatar into it lit by the light the CNN estimates "
        "(3D path), make it perform a generated person's fitted walk (motion transfer), and compare the 2D and 3D "
        "paths against ground truth on generated sequences.",
        "  relightnet demo\n  relightnet demo --out /tmp/demo --size 128 --frames 12 --compare-clips 1\n",
    )
    p.add_argument("--out", default="out/demo", help="output folder (default: %(default)s)")
    p.add_argument("--size", type=pos_int, default=256,
                   help="target clip size, a multiple of 16 (default: %(default)s)")
    p.add_argument("--frames", type=pos_int, default=48, help="frames of the target clip (default: %(default)s)")
    p.add_argument("--n-dirs", type=pos_int, default=64, help="PRT directions (default: %(default)s)")
    p.add_argument("--compare-clips", type=pos_int, default=2,
                   help="generated sequences compared (default: %(default)s)")
    p.add_argument("--compare-size", type=pos_int, default=128, help="their size (default: %(default)s)")
    p.add_argument("--compare-frames", type=pos_int, default=24, help="their length (default: %(default)s)")
    p.set_defaults(func=run)
