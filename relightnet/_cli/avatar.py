"""``relightnet avatar``: put a relit avatar into a target video (pipeline job 3, the 3D path)."""

from __future__ import annotations

import argparse
import logging

from ..errors import InputError
from ..names import LIGHT_FROM, MOTION_KINDS, OUTFITS, VIDEO_SMOOTHING, smoothing_help
from .argtypes import nonneg_int, pos_int
from .options import LIGHT_HELP, add_command, add_mask_source_arg, add_model_args
from .paths import in_path, out_file

logger = logging.getLogger("relightnet.avatar")

#: The motion of Anny when neither --motion nor --motion-from is given.
DEFAULT_MOTION = "walk"


def run(args: argparse.Namespace) -> int:
    from ..io import video_info
    from ..light import load_light
    from ..pipeline.avatar import avatar
    from ..pipeline.backends import make_predictor
    from ..pipeline.scene import load_camera
    from ..pipeline.settings import AvatarLook, AvatarPlacement, VideoLightSettings
    from ..prt import PrtSettings
    from ..sh.io import check_light_physics

    out = out_file(args.out, suffixes=(".mp4", ".mkv"),
                   inputs=(args.target, args.target_masks, args.plate, args.camera, args.albedo, args.motion_from,
                           args.light, args.checkpoint, args.avatar))
    for option, value in (("--target-masks", args.target_masks), ("--plate", args.plate),
                          ("--camera", args.camera), ("--albedo", None if args.albedo == "default" else args.albedo)):
        if value:
            in_path(value, option)
    info = video_info(args.target)  # fail early, before loading the model
    motion = args.motion or DEFAULT_MOTION
    if args.motion_from:
        if args.motion or args.body != "anny":
            raise InputError("--motion-from: the motion comes from the source video; it drives Anny "
                             "(drop --motion and --body)")
        from ..fit.job import motion_for_avatar

        motion = motion_for_avatar(in_path(args.motion_from, "--motion-from", "a video or photo of a person"))
    if args.light and args.light_from != "person":
        raise InputError(f"--light-from {args.light_from}: give --light or --light-from, not both")
    light = check_light_physics(load_light(args.light), args.light) if args.light else None
    plate_light = None
    if args.light_from in ("plate", "both"):  # the plate given, else the target's first frame
        from ..light.plate import load_plate

        plate_light = load_plate(args.plate or args.target, hfov_deg=args.fov)
        if args.light_from == "plate":
            light = plate_light.light
    predictor = None if light is not None else make_predictor(args.backend, args.checkpoint, args.device)
    camera = load_camera(args.camera, info.size) if args.camera else None
    captured = in_path(args.avatar, "--avatar", "an avatar file from `relightnet capture`") if args.avatar else None
    look = AvatarLook(body=args.body, albedo=args.albedo, outfit=args.outfit, captured=captured,
                      antialias=args.antialias)
    lights = VideoLightSettings(smoothing=args.smoothing, mask_source=args.mask_source,
                                model_name=f"{args.backend}:{args.checkpoint or 'shipped'}",
                                plate_light=plate_light if args.light_from == "both" else None)
    prt = PrtSettings(n_dirs=args.n_dirs, occlusion=not args.no_occlusion, bounces=args.bounces)
    placement = AvatarPlacement(plate=args.plate, camera=camera, replace_person=args.replace_person)
    res = avatar(args.target, out, model=predictor, motion=motion, look=look, target_masks=args.target_masks,
                 light=light, lights=lights, prt=prt, placement=placement, progress=not args.quiet, hdr=args.hdr)
    logger.info("wrote %s (%d frames); lights %s; light curves %s", res.video, res.n_frames, res.lights_file, res.plot)
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "avatar",
        "Put an avatar into a target video, lit by the target's light: the CNN estimates the light of every "
        "frame from the person in it, the estimates are smoothed over time, and the avatar is rendered with "
        "PRT transport under that light and composited over the frames (3D path).",
        "  relightnet avatar --target clip.mp4 --motion walk --out avatar.mp4   # masks: person segmentation\n"
        "  relightnet avatar --target clip.mp4 --target-masks masks/ --motion walk --out avatar.mp4\n"
        "  relightnet avatar --target clip.mp4 --body smpl:SMPL_NEUTRAL.npz --motion dance.npz "
        "--albedo skin.png --out a.mp4\n"
        "  relightnet avatar --target clip.mp4 --light sunset --camera cam.json --bounces 1 --out a.mp4\n"
        "  relightnet avatar --target clip.mp4 --replace-person --outfit casual --out avatar.mp4\n"
        "  relightnet avatar --motion-from dancer.mp4 --target clip.mp4 --out transfer.mp4\n"
        "  relightnet avatar --avatar me.avatar.npz --motion-from dancer.mp4 --target clip.mp4 --out me_dancing.mp4\n"
        "  relightnet avatar --target empty_room.mp4 --light-from plate --out a.mp4   # no person to read\n"
        "  relightnet avatar --target clip.mp4 --plate room.jpg --light-from both --out a.mp4\n"
        "  relightnet avatar --target iphone_hlg.mov --motion walk --hdr --out avatar_hdr.mp4   # HDR kept\n",
    )
    p.add_argument("--target", required=True, help="target video (its size and frame rate are kept)")
    p.add_argument("--target-masks", help="masks of the person in the target: folder of images or a mask video "
                   "(default: the person segmentation, tracked from frame to frame; --mask-source)")
    add_mask_source_arg(p)
    p.add_argument("--plate", help="composite over this clean-plate video (or image) of the scene instead of the "
                   "target's frames")
    p.add_argument("--replace-person", action="store_true",
                   help="put the avatar in place of the target's person: composite over the target's clean plate "
                   "(temporal median of the background where the person's mask uncovers it; never-uncovered pixels "
                   "inpainted; OUT.plate.png) with the avatar standing where the person stood; needs a fixed camera (a "
                   "moving one is refused)")
    p.add_argument("--motion", default=None,
                   help=f"Anny preset ({', '.join(MOTION_KINDS)}; as long as the video), an Anny motion file from "
                   "`relightnet fit`, or an SMPL-style motion file (.npz/.pkl) for --body smpl:PATH "
                   f"(default: {DEFAULT_MOTION})")
    p.add_argument("--motion-from", metavar="SOURCE",
                   help="motion transfer: fit the person in this video (or photo) and let the avatar perform "
                   "the motion (retargeted to its body, feet held on the ground)")
    p.add_argument("--body", default="anny", help="'anny' (default) or 'smpl:PATH' to a user-supplied SMPL file")
    p.add_argument("--albedo", default="default", help="texture image in the body's UV layout, or 'default'")
    p.add_argument("--avatar", metavar="FILE.avatar.npz",
                   help="the performer is a person captured by `relightnet capture` (their shape, clothes as "
                   "offsets and de-lit texture), lit by the target's light")
    p.add_argument("--outfit", metavar="NAME|random:SEED",
                   help="dress the avatar in clothes and hair as geometry, with their own albedo: "
                   f"{', '.join(OUTFITS)}, or random:SEED (a drawn outfit)")
    p.add_argument("--light", help="skip the estimation and use this light: " + LIGHT_HELP
                   + "; or a light sequence file with one light per frame")
    p.add_argument("--light-from", choices=LIGHT_FROM, default="person",
                   help="where the light comes from: person (the CNN on the person in every frame; default), plate "
                        "(an environment map made from the background: --plate, else the target's first frame), or "
                        "both (the person's light on the camera side, the plate's on the far side)")
    p.add_argument("--fov", type=float, default=60.0,
                   help="with --light-from plate/both: the plate camera's horizontal field of view "
                        "(default: %(default)g)")
    p.add_argument("--camera", help='camera JSON {"eye": [x,y,z], "target": [x,y,z], "fov_deg": 35} '
                   "(default: full body at the origin)")
    p.add_argument("--smoothing", default="auto", choices=VIDEO_SMOOTHING,
                   help=smoothing_help(VIDEO_SMOOTHING, "auto"))
    p.add_argument("--n-dirs", type=pos_int, default=64, help="PRT ray directions per vertex (default: %(default)s)")
    p.add_argument("--bounces", type=nonneg_int, default=0, help="interreflection bounces (default: %(default)s)")
    p.add_argument("--no-occlusion", action="store_true", help="cosine transport without visibility")
    p.add_argument("--antialias", action=argparse.BooleanOptionalAction, default=True,
                   help="smooth the avatar's silhouette against the background (default: on; ~24 ms per 512² frame)")
    p.add_argument("--hdr", action="store_true",
                   help="keep an HDR target (HLG or PQ) HDR: the avatar over the target's own HDR frames, 10-bit "
                        "BT.2020 with its transfer, HEVC in .mp4, ffv1 in .mkv (default: tone-mapped to SDR, as the "
                        "frames are read); not with --plate or --replace-person")
    p.add_argument("--out", required=True, help="output video (.mp4/.mkv); OUT.lights.npz/.png are written beside it")
    add_model_args(p)
    p.set_defaults(func=run)
