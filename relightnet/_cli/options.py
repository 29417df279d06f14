"""Options shared by several commands, and the command's frame (``--help`` with examples).

Each helper adds one group of options to a command's parser; the names they offer come from
:mod:`relightnet.names` (torch-free).
"""

from __future__ import annotations

import argparse

from ..errors import InputError
from ..names import MASK_SOURCES, MOTION_KINDS, POSE_PRESETS, light_presets
from .argtypes import phenotype_arg, pos_int

__all__ = ["add_command", "no_subcommand", "LIGHT_HELP", "method_options", "check_method_options", "MASK_SOURCE_HELP",
           "add_mask_source_arg", "add_model_args", "add_body_args"]


def add_command(sub, name: str, help: str, examples: str) -> argparse.ArgumentParser:
    """Add a subcommand whose --help ends with copy-pasteable examples."""
    return sub.add_parser(
        name,
        help=help,
        description=help,
        epilog="examples:\n" + examples,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )


def no_subcommand(parser: argparse.ArgumentParser):
    """The ``func`` of a command given without its subcommand: print the command's help, exit status 2."""

    def run(args: argparse.Namespace) -> int:
        parser.print_help()
        return 2

    return run


LIGHT_HELP = (
    "a light: .npz/.json (relightnet), .npy (Kanamori-Endo, BGR), .exr/.hdr environment map, "
    f"a preset name ({', '.join(light_presets())}), "
    "or words: 'key:az=-40,el=30,size=20,color=1/0.9/0.8,power=3 + fill:az=60,power=0.5 + ambient:0.2'"
)


def method_options(p: argparse.ArgumentParser, uses: dict[str, tuple[str, ...]]) -> None:
    """Record which methods each option of ``p`` applies to (``uses``: option dest → method names),
    for :func:`check_method_options` (call after the options are added: it reads their defaults)."""
    p.set_defaults(method_options={dest: (methods, p.get_default(dest)) for dest, methods in uses.items()})


def check_method_options(args: argparse.Namespace, method: str, option: str = "--smoothing") -> None:
    """Refuse an option given with a value for a method it does not apply to (it would be ignored)."""
    for dest, (methods, default) in getattr(args, "method_options", {}).items():
        if getattr(args, dest) != default and method not in methods:
            raise InputError(f"--{dest.replace('_', '-')}: applies to {option} {' / '.join(methods)}, "
                             f"not {method} (it would be ignored)")


MASK_SOURCE_HELP = ("where the person's mask comes from when none is given (and a photo has no alpha): "
                    "'segment' (default): the shipped person segmentation; 'head': the CNN's mask head")


def add_mask_source_arg(p: argparse.ArgumentParser) -> None:
    """--mask-source segment|head: what finds the person when the user gives no mask."""
    p.add_argument("--mask-source", default="segment", choices=MASK_SOURCES, help=MASK_SOURCE_HELP)


def add_model_args(p: argparse.ArgumentParser, backend: bool = True, device: bool = True) -> None:
    """--checkpoint, and --backend and --device when asked: where the CNN comes from and runs."""
    p.add_argument("--checkpoint", help="model checkpoint (.pt; or .onnx with --backend onnx; default: the shipped "
                   "model)" if backend else "model checkpoint (default: the shipped model)")
    if backend:
        p.add_argument("--backend", default="torch", choices=("torch", "onnx"),
                       help="run the CNN in PyTorch or in ONNX Runtime (exported once and cached; "
                            "default: %(default)s)")
    if device:
        p.add_argument("--device", default="cpu", help="cpu or cuda (" + ("torch backend; " if backend else "")
                       + "default: %(default)s)")


def add_body_args(p: argparse.ArgumentParser, fps_help: str = "video frame rate (default: 30)") -> None:
    """--body, --pose, --motion, --frames, --fps, --phenotype: the posed body of render-body and blender-export."""
    p.add_argument("--body", default="anny", help="'anny' (default) or 'smpl:PATH' to a user-supplied SMPL file")
    p.add_argument("--pose", default="arms_down", choices=POSE_PRESETS, metavar="POSE",
                   help=f"pose preset of a still Anny body: {', '.join(POSE_PRESETS)} (default: %(default)s)")
    p.add_argument("--motion", help=f"procedural motion for Anny ({', '.join(MOTION_KINDS)}) or an SMPL-style "
                   "motion file (.npz/.pkl with poses (T,72), betas (10,), trans (T,3)) for --body smpl:PATH")
    p.add_argument("--frames", type=pos_int, default=60, help="frames of a procedural motion (default: %(default)s)")
    p.add_argument("--fps", type=float, default=30.0, help=fps_help)
    p.add_argument("--phenotype", type=phenotype_arg, action="append", metavar="NAME=VALUE",
                   help="Anny phenotype value (gender, age, muscle, weight, height, proportions); repeatable")
