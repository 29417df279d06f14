"""``relightnet capture``: a filmed person → an avatar file (geometry beyond the body, a de-lit texture)."""

from __future__ import annotations

import argparse
import logging

from ..errors import InputError
from ..names import VIDEO_SMOOTHING, smoothing_help
from .argtypes import pos_float, pos_int
from .options import add_command, add_model_args
from .paths import in_path, out_file

logger = logging.getLogger("relightnet.capture")


def run(args: argparse.Namespace) -> int:
    src = in_path(args.input, "SOURCE", "a video or a photo of a person")
    if not str(args.out).endswith(".avatar.npz"):
        raise InputError(f"--out {args.out}: expected a file name ending in .avatar.npz")
    out = out_file(args.out, "--out", (".npz",), inputs=(args.input, args.checkpoint))
    preview = out_file(args.preview, "--preview", (".png",), inputs=(args.input,)) if args.preview else None
    from ..io.probe import PHOTO_SUFFIXES

    kinds = (".png",) if src.suffix.lower() in PHOTO_SUFFIXES else (".mp4", ".mkv")
    checks = {opt: out_file(val, opt, kinds, inputs=(args.input,)) if val else None
              for opt, val in (("--reproject", args.reproject), ("--mask-out", args.mask_out))}
    import torch

    from ..capture.texture import TextureOptions
    from ..fit import FitBody, FitOptions
    from ..pipeline.backends import make_predictor
    from ..pipeline.capture_job import CaptureOptions, capture_file
    from ..segment import PersonModels

    if args.threads:  # the command owns its process: --threads holds for the whole run
        torch.set_num_threads(args.threads)
    texture = TextureOptions(size=args.texture_size)  # a bad size fails before the model is loaded
    predictor = make_predictor(args.backend, args.checkpoint, args.device)
    opts = CaptureOptions(texture=texture, fit=FitOptions(fov_deg=args.fov), offsets=False if args.no_offsets else None,
                          smoothing=args.smoothing)
    fb = FitBody()
    rep = capture_file(src, out, predictor, opts, preview, PersonModels(threads=args.threads or 0), fb=fb)
    logger.info("wrote %s: %.1f%% of the surface seen over %d frame(s)%s", rep.out, 100 * rep.avatar.seen_share,
                rep.avatar.frames, "" if rep.iou_body is None else
                f"; silhouette IoU {rep.iou_body:.3f} bare, {rep.iou_offset:.3f} captured")
    if preview:
        logger.info("wrote %s", preview)
    if checks["--reproject"] or checks["--mask-out"]:
        from ..pipeline.capture_check import reproject

        r = reproject(rep, src, fb, checks["--reproject"], checks["--mask-out"])
        logger.info("reprojected over %d frame(s): %.1f dB inside the person, silhouette IoU %.3f%s", r.frames,
                    r.psnr, r.iou, "".join(f"; wrote {p}" for p in checks.values() if p))
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "capture",
        "Capture the largest person of a video (or a photo) as an avatar: the fitted Anny body grown by per-vertex "
        "offsets to the person's silhouettes (clothes, hair) and an albedo texture in Anny's UV layout, each frame "
        "divided by the shading of that geometry under the frame's estimated light and fused over the frames. "
        "avatar --avatar and render-body --avatar make the captured person perform.",
        "  relightnet capture walk.mp4 --out person.avatar.npz --preview sheet.png\n"
        "  relightnet avatar --avatar person.avatar.npz --target clip.mp4 --motion-from walk.mp4 --out moved.mp4\n"
        "  relightnet render-body --avatar person.avatar.npz --pose apose --light studio --out person.png\n",
    )
    p.add_argument("input", metavar="SOURCE", help="a video (a person turning shows every side) or a photo")
    p.add_argument("--out", required=True, help="the avatar file (NAME.avatar.npz; arrays only, see the README)")
    p.add_argument("--preview", metavar="PNG", help="draw the texture, its confidence and the avatar from four sides")
    p.add_argument("--reproject", metavar="VIDEO", help="the captured avatar re-rendered in the source's camera, "
                   "poses and light over its frames (.mp4/.mkv; .png for a photo); logs the PSNR inside the person")
    p.add_argument("--mask-out", metavar="VIDEO", help="the captured mesh's silhouette in the source camera (a mask "
                   "video .mkv/.mp4; .png for a photo)")
    p.add_argument("--texture-size", type=pos_int, default=1024, help="texture side in texels (default: %(default)s)")
    p.add_argument("--no-offsets", action="store_true", help="keep the bare fitted body (no geometry beyond it)")
    p.add_argument("--smoothing", default="auto", choices=VIDEO_SMOOTHING,
                   help=smoothing_help(VIDEO_SMOOTHING, "auto"))
    p.add_argument("--fov", type=pos_float, default=60.0,
                   help="field of view (degrees) across the longer side when the source has no EXIF focal length "
                   "(default: %(default)g); the captured height follows it (a narrower lens read as 60° makes a taller "
                   "person)")
    p.add_argument("--threads", type=pos_int, default=None, help="torch and ONNX Runtime threads (default: all)")
    add_model_args(p)
    p.set_defaults(func=run)
