"""``relightnet segment``: person masks (and body landmarks) of a photo, a folder of photos or a video."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from ..errors import InputError
from .argtypes import nonneg_int
from .options import add_command
from .paths import in_path, out_dir, out_file

logger = logging.getLogger("relightnet.segment")


def run(args: argparse.Namespace) -> int:
    from ..segment import PersonModels
    from ..segment.jobs import segment_files

    src = in_path(args.input, "INPUT", "a photo, a folder of photos or a video")
    out = out_file(args.out, inputs=(src,)) if Path(args.out).suffix else out_dir(args.out)
    if args.landmarks:
        out_file(args.landmarks, "--landmarks", (".npz",), inputs=(src,))
    if not 0 <= args.steady < 0.5:  # refused before the models load
        raise InputError(f"--steady: expected a probability margin in [0, 0.5), got {args.steady}")
    segment_files(src, out, PersonModels(threads=args.threads), args.landmarks, args.allow_empty, args.smoothing,
                  progress=logger.isEnabledFor(logging.INFO), steady=args.steady, soft=args.soft)
    logger.info("wrote %s", out)
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "segment",
        "Person masks from the shipped segmentation models (MediaPipe, Apache-2.0, in ONNX Runtime): a photo "
        "gives a PNG mask, a folder of photos a folder of masks, a video a mask video (or a folder of frame "
        "masks; the person is tracked from frame to frame). The largest person is taken.",
        "  relightnet segment person.jpg --out person_mask.png\n"
        "  relightnet segment photos/ --out masks/ --landmarks landmarks.npz\n"
        "  relightnet segment person.jpg --soft --out person_alpha.png   # soft edges (gray alpha)\n"
        "  relightnet segment clip.mp4 --out clip_masks.mkv            # lossless mask video, one mask per frame\n"
        "  relightnet segment clip.mp4 --out masks/ --allow-empty     # frame_00000.png, ...\n",
    )
    p.add_argument("input", help="a photo (PNG/JPEG), a folder of photos or a video")
    p.add_argument("--out", required=True, help="mask PNG (photo), folder (photos or video) or mask video .mkv/.mp4")
    p.add_argument("--landmarks", metavar="FILE.npz",
                   help="also save the 33 body landmarks per photo/frame: landmarks (T, 33, 5) x, y in pixels, "
                   "z, visibility, presence; world (T, 33, 3) metres; score, found (T,); names (33,)")
    p.add_argument("--allow-empty", action="store_true",
                   help="photos/frames without a person get an empty mask (default: an error naming them)")
    p.add_argument("--smoothing", type=float, default=0.5,
                   help="video: weight of the new frame in the tracked crop (1: no smoothing; default: 0.5)")
    p.add_argument("--steady", type=float, default=0.15,  # relightnet.segment.steady.STEADY_MARGIN (torch-free here)
                   help="video: hold the mask's outline steady over time: a pixel near the previous mask's outline "
                   "(carried along the landmarks' motion) keeps its state unless its probability is this far past "
                   "one half (0: off; default: 0.15)")
    p.add_argument("--soft", action="store_true",
                   help="photos: write the soft matte (the segmentation's probability refined on the photo in a "
                   "narrow band around the outline; 8-bit gray PNG) instead of the binary mask")
    p.add_argument("--threads", type=nonneg_int, default=0,
                   help="ONNX Runtime threads (default: %(default)s, all cores)")
    p.set_defaults(func=run)
