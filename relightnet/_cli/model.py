"""``relightnet train``, ``evaluate`` (its reports: relightnet/_cli/evaluate.py) and ``estimate-light``."""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from ..errors import InputError
from .argtypes import work_size
from .evaluate import register as register_evaluate
from .inputs import read_photo
from .options import add_command, add_mask_source_arg, add_model_args
from .paths import out_dir, out_file

logger = logging.getLogger("relightnet.model")

#: The plate's horizontal field of view in degrees when --fov is not given.
PLATE_FOV = 60.0


def run_train(args: argparse.Namespace) -> int:
    from ..model.training import load_train_config, train

    cfg = load_train_config(args.config)
    if not Path(args.data, "manifest.json").is_file():
        raise InputError(f"--data {args.data}: expected a dataset folder made by 'relightnet synth' (no manifest.json)")
    out = out_dir(args.out)
    last = train(cfg, args.data, out, resume=args.resume, device=args.device, resume_from=args.resume_from,
                 candidate=out_file(args.candidate, "--candidate", (".pt",)) if args.candidate else None)
    logger.info("training finished: %s", json.dumps({k: round(v, 5) for k, v in last.items()}) if last else "-")
    return 0


def run_estimate_light(args: argparse.Namespace) -> int:
    from ..checks import InputError
    from ..light.plate import combine_person_plate, load_plate
    from ..pipeline.backends import make_predictor
    from ..sh import save_light
    from ..sh.io import LIGHT_SUFFIXES

    if args.image is None and args.plate is None:
        raise InputError("give a photo of a person (IMAGE), a background plate (--plate), or both")
    if args.fov is not None and args.plate is None:
        raise InputError("--fov is the plate's field of view: give --plate")
    out = out_file(args.out, suffixes=LIGHT_SUFFIXES)
    plate = None
    if args.plate is not None:
        plate = load_plate(args.plate, hfov_deg=args.fov or PLATE_FOV)
    light = None
    if args.image is not None:
        image, mask, _ = read_photo(args.image, args.mask, args.mask_source)
        predict = make_predictor(args.backend, args.checkpoint, args.device, size=args.size)
        light = predict.light(image, mask).cpu()
    if plate is not None:
        light = plate.light if light is None else combine_person_plate(light, *plate)
    save_light(out, light)
    logger.info("wrote %s (light from %s)", out, " and ".join(
        w for w, v in (("the person", args.image), ("the plate", args.plate)) if v is not None))
    return 0


def register(sub) -> None:
    p = add_command(sub, "train", "Train the inverse-rendering CNN on a synthetic dataset (resumable; torchrun-ready).",
                    "  relightnet train --config train/configs/small.yaml --data data/synth --out runs/small\n"
                    "  relightnet train --config train/configs/small.yaml --data data/synth --out runs/small --resume\n"
                    "  torchrun --nproc_per_node=2 -m train --config train/configs/small.yaml --data data/synth "
                    "--out runs/ddp\n")
    p.add_argument("--config", required=True, help="training config (YAML)")
    p.add_argument("--data", required=True, help="dataset folder made by 'relightnet synth'")
    p.add_argument("--out", required=True, help="run folder: checkpoints (last.pt), metrics.jsonl, loss.png")
    p.add_argument("--resume", action="store_true", help="continue from OUT/last.pt")
    p.add_argument("--resume-from", metavar="CKPT", default=None,
                   help="continue from this checkpoint (a committed candidate, train/checkpoints/) while OUT has "
                        "no last.pt; then from OUT/last.pt")
    p.add_argument("--candidate", metavar="PATH", default=None,
                   help="also write the run's carry-over checkpoint here at every checkpoint (weights, step, "
                        "schedule, config and data recipe; no optimiser state; at most 15 MB)")
    p.add_argument("--device", default="cpu", help="cpu or cuda (default: %(default)s)")
    p.set_defaults(func=run_train, interrupt_hint=lambda a: f"run the same command with --resume to continue "
                   f"from {a.out}/last.pt")

    register_evaluate(sub)

    p = add_command(sub, "estimate-light", "Estimate the SH light of a photo of a person (the CNN), of a "
                    "background plate (an environment map made from the photo itself), or of both combined.",
                    "  relightnet estimate-light person.jpg --out light.npz        # mask: person segmentation\n"
                    "  relightnet estimate-light --plate background.jpg --out plate_light.npz\n"
                    "  relightnet estimate-light person.jpg --plate background.jpg --fov 50 --out both.npz\n"
                    "  relightnet estimate-light person.jpg --mask person_mask.png --out light.npz\n"
                    "  relightnet estimate-light person.png --out light_ke18.npy    # Kanamori-Endo format (BGR)\n")
    p.add_argument("image", nargs="?", help="image file (PNG/JPEG) of a person")
    p.add_argument("--plate", help="background plate (image, or a video's first frame): its light, read from the "
                   "picture itself (with IMAGE: the plate where its frame shows the light, the person's estimate "
                   "elsewhere)")
    p.add_argument("--fov", type=float, default=None, help="the plate's horizontal field of view in degrees "
                   f"(default: {PLATE_FOV:g})")
    p.add_argument("--mask", help="mask of the person (white = person, or its alpha); default: the photo's alpha "
                   "if it has one, else the person segmentation (--mask-source)")
    add_mask_source_arg(p)
    p.add_argument("--out", required=True, help="light file: .npz/.json (ours) or .npy (Kanamori-Endo)")
    p.add_argument("--size", type=work_size, default=None,
                   help="working resolution, a multiple of 16 (default: the size the model was trained at)")
    add_model_args(p)
    p.set_defaults(func=run_estimate_light)
