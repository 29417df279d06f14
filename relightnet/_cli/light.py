"""``relightnet light show|convert``: look at a light, convert between light formats."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from .argtypes import exposure_arg, image_size, nonneg_int
from .options import LIGHT_HELP, add_command, no_subcommand
from .paths import out_file

logger = logging.getLogger("relightnet.light")

def _envmap_of(light: str):
    """The original environment map behind a light argument, if it has one."""
    from ..io.envmap import ENVMAP_SUFFIXES, read_envmap
    from ..light.presets import preset_envmap, preset_names
    from ..light.words import is_light_words, words_envmap

    if is_light_words(light) and not Path(light).exists():
        return words_envmap(light)
    p = Path(light)
    if p.suffix.lower() in ENVMAP_SUFFIXES and p.is_file():
        return read_envmap(p)
    if light in preset_names():
        return preset_envmap(light)
    return None


def run_show(args: argparse.Namespace) -> int:
    from ..io.image import write_image
    from ..light import load_light
    from ..light.visualize import light_preview

    out = out_file(args.out, suffixes=(".png",))
    sh = load_light(args.light, lmax=args.lmax)
    env = _envmap_of(args.light) if sh.dim() == 2 else None
    img = light_preview(sh, size=args.size, env=env, exposure=args.exposure)
    write_image(out, img)
    what = f"{tuple(sh.shape)} light" if sh.dim() == 2 else f"sequence of {sh.shape[0]} lights"
    logger.info("wrote %s (%dx%d) for %s %s", out, img.shape[1], img.shape[0], what, args.light)
    return 0


def run_convert(args: argparse.Namespace) -> int:
    from ..light import load_light
    from ..sh.io import LIGHT_SUFFIXES, save_light

    out = out_file(args.output, "OUT", LIGHT_SUFFIXES, inputs=(args.input,))
    sh = load_light(args.input, lmax=args.lmax)
    save_light(out, sh)
    logger.info("wrote %s: %s light from %s", out, tuple(sh.shape), args.input)
    return 0


def register(sub) -> None:
    light = add_command(
        sub,
        "light",
        "Show a spherical-harmonics light as a picture, or convert it between file formats.",
        "  relightnet light show studio --out studio.png\n"
        "  relightnet light show 'key:az=-40,el=30,size=20,power=3 + ambient:0.2' --out key.png\n"
        "  relightnet light show my_light.npz --out my_light.png --exposure 2\n"
        "  relightnet light convert relightnet/data/envmaps/sunset.exr sunset.npz --lmax 3\n"
        "  relightnet light convert kanamori_light.npy light.json\n",
    )
    light.set_defaults(func=no_subcommand(light))
    lsub = light.add_subparsers(dest="light_command", metavar="{show,convert}")

    show = add_command(
        lsub,
        "show",
        "Write a PNG preview of a light: a white diffuse sphere seen from the front and from the back, "
        "the light's lat-long reconstruction, and the original environment map when there is one.",
        "  relightnet light show sunset --out sunset.png\n"
        "  relightnet light show 'key:az=-40,el=30,size=20,color=1/0.9/0.8,power=3 + fill:az=60,power=0.5' "
        "--out key.png\n"
        "  relightnet light show light.npy --out light.png --size 128\n"
        "  relightnet light show lights_over_time.npz --out seq.png   # up to 8 frames as spheres\n",
    )
    show.add_argument("light", help=LIGHT_HELP)
    show.add_argument("--out", default="light.png", help="output .png (default: %(default)s)")
    show.add_argument(
        "--lmax", type=nonneg_int, default=None,
        help="SH order: projection order for env maps/presets (default 2); truncates/pads stored lights",
    )
    show.add_argument(
        "--exposure", type=exposure_arg, default="auto",
        help="'auto' (sphere 99th percentile at 0.9) or a linear multiplier (default: %(default)s)",
    )
    show.add_argument("--size", type=image_size, default=256, help="sphere size in pixels (default: %(default)s)")
    show.set_defaults(func=run_show)

    conv = add_command(
        lsub,
        "convert",
        "Convert a light between formats, chosen by the output extension: .npz or .json (relightnet, "
        "any order, sequences too) or .npy (Kanamori-Endo, one order-2 light, BGR columns).",
        "  relightnet light convert studio studio.npz\n"
        "  relightnet light convert kanamori_light.npy light.npz\n"
        "  relightnet light convert light.npz kanamori_light.npy\n"
        "  relightnet light convert scene.exr scene.json --lmax 4\n",
    )
    conv.add_argument("input", metavar="IN", help=LIGHT_HELP)
    conv.add_argument("output", metavar="OUT", help="output file: .npz, .json or .npy")
    conv.add_argument(
        "--lmax", type=nonneg_int, default=None,
        help="SH order: projection order for env maps/presets (default 2); truncates/pads stored lights",
    )
    conv.set_defaults(func=run_convert)
