"""``relightnet blender-export`` (avatar scene → .blend) and ``relightnet blender-render`` (Cycles frames)."""

from __future__ import annotations

import argparse
import logging

from .argtypes import exposure_arg, nonneg_int, pos_int
from .options import LIGHT_HELP, add_body_args, add_command
from .paths import out_dir, out_file

logger = logging.getLogger("relightnet.blender")


def _frames_arg(text: str) -> tuple[int | None, int | None]:
    a, sep, b = text.partition(":")
    try:
        if not sep:
            i = int(a)
            return i, i + 1
        return (int(a) if a else None), (int(b) if b else None)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected START:END (frame indices from 0, END excluded), got {text!r}") \
            from None


def _body_params(args, body):
    """Per-frame parameters of the body: a motion (preset or file) or a still pose preset."""
    from ..checks import InputError
    from ..pipeline.scene import motion_params

    if args.motion:
        params, _ = motion_params(args.motion, body, args.frames, fps=args.fps, seed=args.seed)
    elif hasattr(body, "pose"):
        params = {"pose": body.pose(args.pose)}
    elif args.pose != "arms_down":
        raise InputError(f"--pose {args.pose}: pose presets are for Anny; give an SMPL body a --motion file")
    else:
        params = {}
    if args.phenotype:
        if not hasattr(body, "phenotype_tensor"):
            raise InputError("--phenotype: phenotypes are Anny's; an SMPL body takes its betas from the model file")
        params["phenotype"] = dict(args.phenotype)
    return params


def _camera(spec: str, size: int):
    if spec in ("default", "fit"):
        return None if spec == "default" else "fit"
    from ..pipeline.scene import load_camera

    return load_camera(spec, size)


def run_export(args: argparse.Namespace) -> int:
    from ..blender import CyclesSettings, WorldLightSettings, export_body_scene
    from ..pipeline.scene import avatar_albedo, load_body
    from .inputs import load_single_light

    out = out_file(args.out, suffixes=(".blend",))
    load_single_light(args.light)  # fail fast on a bad light, before building the body
    body = load_body(args.body)
    params = _body_params(args, body)
    albedo = avatar_albedo(body, args.albedo)
    camera = _camera(args.camera, args.res)
    world = WorldLightSettings(light_frame=args.light_frame, band_limit=args.band_limit, lmax=args.lmax,
                               size=args.world_res, negative=args.negative)
    export_body_scene(out, body, params, args.light, albedo=albedo, camera=camera, size=args.res, fps=args.fps,
                      world=world, cycles=CyclesSettings(spp=args.spp, bounces=args.bounces))
    logger.info("wrote %s", out)
    return 0


def run_render(args: argparse.Namespace) -> int:
    from ..blender import render_blend

    out = out_dir(args.out)
    n = 0
    for fr in render_blend(args.blend, out, spp=args.spp, bounces=args.bounces, frames=args.frames,
                           threads=args.threads, denoise=args.denoise, filter_width=args.filter_width, seed=args.seed,
                           exposure=args.exposure, progress=not args.quiet):
        n += 1
        logger.debug("frame %d rendered in %.2f s", fr.index, fr.seconds)
    logger.info("wrote %d frame(s) to %s (frame_NNNNN.exr linear RGBA, frame_NNNNN.png 8-bit sRGB)", n, args.out)
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "blender-export",
        "Export the avatar scene to a Blender .blend: the posed (or animated) body with UVs and its albedo "
        "texture on a diffuse material, the world lit by the light (the full environment map, or the lat-long "
        "image of an SH light), and a camera equal to relightnet's (intrinsics, extrinsics, size, frame rate). "
        "Needs the 'relightnet[blender]' extra (bpy).",
        "  relightnet blender-export --pose arms_crossed --light studio --out avatar.blend\n"
        "  relightnet blender-export --motion walk --frames 48 --fps 24 --light sunset --res 256 --out walk.blend\n"
        "  relightnet blender-export --pose apose --light estimated.npz --negative lift --camera fit --out a.blend\n"
        "  relightnet blender-export --pose tpose --light city --band-limit --out city_sh.blend\n"
        "  relightnet blender-export --body smpl:SMPL_NEUTRAL.npz --motion clip.npz --albedo skin.png "
        "--light sky.exr --camera cam.json --out clip.blend\n",
    )
    add_body_args(p, fps_help="frame rate of the scene (default: 30); a motion gives one Blender frame per frame")
    p.add_argument("--seed", type=int, default=0, help="seed of procedural motions")
    p.add_argument("--albedo", default="default",
                   help="albedo texture image (sRGB, in the body's UV layout) or 'default' (Anny's outfit)")
    p.add_argument("--light", required=True, help=LIGHT_HELP)
    p.add_argument("--light-frame", default="camera", choices=("camera", "world"),
                   help="the light is relative to the camera (relightnet's avatar convention, default) or fixed "
                   "to the world")
    p.add_argument("--band-limit", action="store_true",
                   help="light an environment-map light by its order-LMAX SH reconstruction (what PRT sees)")
    p.add_argument("--lmax", type=nonneg_int, default=2, help="SH order for --band-limit (default: %(default)s)")
    p.add_argument("--negative", default="clamp", choices=("clamp", "lift"),
                   help="negative radiance of an SH world: clamp to 0 (default) or lift by a constant")
    p.add_argument("--world-res", type=pos_int, default=128,
                   help="rows of the world image of an SH light (width 2x; default: 128)")
    p.add_argument("--camera", default="default",
                   help="'default' (full body, 35° fov), 'fit' (framing the motion from 20° above) or a camera JSON "
                   '{"eye": [x,y,z], "target": [x,y,z], "fov_deg": 35}')
    p.add_argument("--res", type=pos_int, default=512, help="square image size in pixels (default: %(default)s)")
    p.add_argument("--spp", type=pos_int, default=64, help="Cycles samples stored in the file (default: %(default)s)")
    p.add_argument("--bounces", type=nonneg_int, default=4, help="Cycles diffuse bounces stored in the file "
                   "(default: %(default)s)")
    p.add_argument("--out", required=True, help="output .blend file (written atomically)")
    p.set_defaults(func=run_export)

    p = add_command(
        sub, "blender-render",
        "Render a .blend (from blender-export) with Cycles on the CPU: linear EXR (RGBA) and 8-bit sRGB PNG "
        "frames. Pixel values are the scene's radiance; relightnet's own renders are pi times brighter.",
        "  relightnet blender-render avatar.blend --spp 64 --bounces 1 --out frames/\n"
        "  relightnet blender-render walk.blend --frames 0:10 --spp 16 --threads 2 --out walk_frames/\n"
        "  relightnet blender-render avatar.blend --spp 256 --bounces 4 --denoise --exposure 2 --out ref/\n",
    )
    p.add_argument("blend", help="the .blend file")
    p.add_argument("--out", required=True, help="output folder (frame_NNNNN.exr and frame_NNNNN.png)")
    p.add_argument("--spp", type=pos_int, help="samples per pixel (default: the file's)")
    p.add_argument("--bounces", type=nonneg_int, help="diffuse bounces, 0 = direct light only (default: the file's)")
    p.add_argument("--frames", type=_frames_arg, metavar="START:END",
                   help="frame indices from 0, END excluded (default: all frames)")
    p.add_argument("--threads", type=nonneg_int, help="CPU threads (default: the file's; 0 = all cores)")
    p.add_argument("--denoise", action=argparse.BooleanOptionalAction, default=None,
                   help="OpenImageDenoise on/off (default: the file's, off after blender-export)")
    p.add_argument("--filter-width", type=float, help="pixel filter width in pixels (default: the file's, 1.5; "
                   "0.01 samples pixel centres like relightnet's rasterizer)")
    p.add_argument("--seed", type=int, help="Cycles noise seed (default: the file's)")
    p.add_argument("--exposure", type=exposure_arg, default="auto",
                   help="PNG exposure: 'auto' (set on the first frame) or a linear multiplier (EXR is not scaled)")
    p.set_defaults(func=run_render)
