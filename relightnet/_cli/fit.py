"""``relightnet fit``: fit the Anny body to the person in a photo or a video → an Anny motion file."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from ..io.probe import PHOTO_SUFFIXES
from .argtypes import pos_float, pos_int
from .options import add_command
from .paths import in_path, out_file

logger = logging.getLogger("relightnet.fit")

_VIDEO = (".mp4", ".mkv")


def _outputs(args, photo: bool):
    out = out_file(args.out, "--out", (".npz",), inputs=(args.input,))
    kinds = (".png",) if photo else _VIDEO
    what = "a .png for a photo" if photo else "a video (.mp4/.mkv) for a video"
    extra = {}
    for opt, val in (("--preview", args.preview), ("--mask-out", args.mask_out)):
        if val:
            if Path(val).suffix.lower() not in kinds:
                raise ValueError(f"{opt} {val}: expected {what}")
            extra[opt] = out_file(val, opt, kinds, inputs=(args.input,))
    return out, extra


def run(args: argparse.Namespace) -> int:
    src = in_path(args.input, "INPUT", "a photo (.png, .jpg, .webp, ...) or a video")
    photo = src.suffix.lower() in PHOTO_SUFFIXES
    out, extra = _outputs(args, photo)
    import torch

    from ..body import save_anny_motion
    from ..fit import FitBody
    from ..fit.job import FitOptions, fit_file, write_fit_masks, write_preview
    from ..segment import PersonModels

    if args.threads:  # the command owns its process: --threads holds for the whole run
        torch.set_num_threads(args.threads)
    opts = FitOptions(iters=args.iters, warm_iters=args.warm_iters, window=args.window, fit_shape=not args.no_shape,
                      smooth_sigma=0.0 if photo else args.smooth, fov_deg=args.fov)
    fb = FitBody()
    res = fit_file(src, opts, fb, PersonModels(threads=args.threads or 0))
    save_anny_motion(out, res.motion)
    T = res.result.pose.shape[0]
    logger.info("wrote %s (%d frame(s) in %.1f s, median landmark residual %.2f%% of the height)", out, T,
                res.raw.seconds, 100 * float(res.raw.residual_2d.median()))
    if "--preview" in extra:
        write_preview(extra["--preview"], src, res.result, fb, res.fps)
        logger.info("wrote %s", extra["--preview"])
    if "--mask-out" in extra:
        write_fit_masks(extra["--mask-out"], res.result, fb, res.fps)
        logger.info("wrote %s", extra["--mask-out"])
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "fit",
        "Fit the Anny body (bone rotations, global orientation and translation, height/weight/proportions) to the "
        "largest person in a photo or a video, from the shipped segmentation's 33 landmarks (pixels and metres) "
        "and mask. Writes an Anny motion file that render-body --motion and avatar --motion read.",
        "  relightnet fit person.jpg --out pose.npz --preview overlay.png\n"
        "  relightnet fit walk.mp4 --out walk_motion.npz --preview overlay.mp4 --mask-out fitted_masks.mkv\n"
        "  relightnet render-body --motion walk_motion.npz --light courtyard --out replay.mp4\n",
    )
    p.add_argument("input", help="a photo (PNG/JPEG) or a video")
    p.add_argument("--out", required=True, help="the motion file (.npz): pose (T, 104, 3), trans (T, 3), "
                   "phenotype (6,), camera_*, residual_2d, interpolated (see the README)")
    p.add_argument("--preview", metavar="FILE", help="the fitted mesh drawn over the input (.png for a photo, "
                   ".mp4/.mkv for a video)")
    p.add_argument("--mask-out", metavar="FILE", help="the fitted body's silhouette in the input's camera (.png for "
                   "a photo, a mask video .mkv/.mp4 for a video)")
    p.add_argument("--iters", type=pos_int, default=120,
                   help="optimiser steps of the first window (default: %(default)s)")
    p.add_argument("--warm-iters", type=pos_int, default=50,
                   help="optimiser steps of each later window, warm-started (default: %(default)s)")
    p.add_argument("--window", type=pos_int, default=8, help="frames fitted together (default: %(default)s)")
    p.add_argument("--smooth", type=float, default=1.5,
                   help="video: Gaussian sigma in frames of the final smoothing pass (0: none; default: 1.5)")
    p.add_argument("--fov", type=pos_float, default=60.0,
                   help="field of view (degrees) across the longer side when the input has no EXIF focal length "
                   "(default: %(default)g)")
    p.add_argument("--no-shape", action="store_true", help="keep the default body shape (fit the pose only)")
    p.add_argument("--threads", type=pos_int, default=None, help="torch and ONNX Runtime threads (default: all)")
    p.set_defaults(func=run)
