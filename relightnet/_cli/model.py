"""``relightnet train``, ``evaluate`` and ``estimate-light``: the CNN of the 2D path."""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from ..errors import InputError
from .argtypes import pos_int, work_size
from .inputs import read_photo
from .options import add_command, add_mask_source_arg, add_model_args
from .paths import out_dir, out_file

logger = logging.getLogger("relightnet.model")


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


def run_evaluate(args: argparse.Namespace) -> int:
    from ..io import atomic_write
    from ..model.checkpoint import load_model
    from ..model.evaluate import baseline_from_train, evaluate, format_ablation, format_table, write_report

    out = out_dir(args.out)
    if args.capture:
        return _evaluate_capture(args, out)
    if args.fit:
        return _evaluate_fit(args, out)
    if args.ship:
        return _evaluate_ship(args, out)
    if (args.data is None) == (args.photos is None):
        raise InputError("--data, --photos: give one, not both" if args.data else
                         "give --data (a dataset folder made by 'relightnet synth') or --photos (a folder of photos)")
    if args.photos is not None:
        return _evaluate_photos(args, out)
    if args.clips and not args.light:
        raise InputError("--clips: only with --light (the light report)")
    unused = [o for o, given in (("--ablation", args.ablation), ("--no-baseline", args.no_baseline),
                                 ("--as-photo", args.as_photo)) if given]
    if args.light and unused:
        raise InputError(f"{', '.join(unused)}: not used with --light (the light report has no baseline or twin)")
    model = load_model(args.checkpoint, device=args.device)
    if args.light:
        return _evaluate_light(args, model, out)
    twin = load_model(args.ablation, device=args.device) if args.ablation else None
    out.mkdir(parents=True, exist_ok=True)
    base = baseline_from_train(args.data) if not args.no_baseline else None
    result = evaluate(model, args.data, split=args.split, baseline=base, sheet=out / "contact_sheet.png", twin=twin,
                      floor=twin is not None, photo=args.as_photo)
    extra = ""
    if twin is not None:
        extra = ("\n\nOcclusion ablation (KE18): --ablation " + str(args.ablation) + " against this model\n\n"
                 + format_ablation(result["model"], result["ablation"], result["occlusion_floor"]))
    write_report(result, out / "report.md", extra)
    logger.info("evaluated %d %s items:\n%s%s", result["n"], args.split, format_table(result), extra)
    with atomic_write(out / "metrics.json", "w") as f:
        json.dump(result, f, indent=2)
    return 0


def _evaluate_light(args: argparse.Namespace, model, out: Path) -> int:
    from ..io import atomic_write
    from ..pipeline.light_eval import evaluate_light, format_light_report

    result = evaluate_light(model, args.data, clips=args.clips or (), split=args.split)
    text = format_light_report(result, str(args.checkpoint or "shipped model"))
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / "light_report.md", "w") as f:
        f.write(f"# Light estimation: {args.checkpoint or 'shipped model'} on {args.data}\n\n{text}")
    with atomic_write(out / "light_metrics.json", "w") as f:
        json.dump(result, f, indent=2)
    logger.info("light report (%s):\n%s", out / "light_report.md", text)
    return 0


def _evaluate_fit(args: argparse.Namespace, out: Path) -> int:
    from ..io import atomic_write
    from ..pipeline.fit_eval import evaluate_fit, format_fit_report

    unused = [o for o, given in (("--data", args.data), ("--photos", args.photos), ("--checkpoint", args.checkpoint),
                                 ("--light", args.light), ("--clips", args.clips), ("--ablation", args.ablation),
                                 ("--no-baseline", args.no_baseline), ("--split", args.split != "test"),
                                 ("--as-photo", args.as_photo)) if given]
    if unused:
        raise InputError(f"{', '.join(unused)}: not used with --fit (it generates its own test clips)")
    result = evaluate_fit(args.fit_clips, args.fit_frames, args.fit_res,
                          progress=lambda i, r: logger.info("clip %d (%s): MPJPE %.1f mm, IoU %.3f", i, r["motion"],
                                                            r["mpjpe"], r["iou_body"]))
    text = format_fit_report(result)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / "fit_report.md", "w") as f:
        f.write(f"# Fitting Anny: {args.fit_clips} generated test clips of {args.fit_frames} frames at "
                f"{args.fit_res}²\n\n{text}\n")
    with atomic_write(out / "fit_metrics.json", "w") as f:
        json.dump(result, f, indent=2)
    print(text)  # the command's own output (stdout), not a log message
    return 0


def _evaluate_capture(args: argparse.Namespace, out: Path) -> int:
    from ..pipeline.backends import make_predictor
    from ..pipeline.capture_eval import evaluate_capture, format_capture_report

    unused = [o for o, given in (("--data", args.data), ("--photos", args.photos), ("--light", args.light),
                                 ("--clips", args.clips), ("--ablation", args.ablation), ("--fit", args.fit),
                                 ("--ship", args.ship), ("--no-baseline", args.no_baseline),
                                 ("--split", args.split != "test"), ("--as-photo", args.as_photo)) if given]
    if unused:
        raise InputError(f"{', '.join(unused)}: not used with --capture (it generates its own people)")
    predictor = make_predictor("torch", args.checkpoint, args.device)
    result = evaluate_capture(predictor, out, args.capture_clips, args.capture_frames, args.capture_res,
                              args.capture_texture,
                              progress=lambda i, r: logger.info("clip %d (seed %d): albedo RMSE %.3f, IoU %.3f, "
                                                                "re-render %.1f dB", i, r["seed"], r["albedo_rmse"],
                                                                r["iou_offset"], r["psnr"]))
    print(format_capture_report(result))  # the command's own output (stdout), not a log message
    logger.info("wrote %s and %s", out / "capture_report.md", out / "capture_metrics.json")
    return 0


def _evaluate_ship(args: argparse.Namespace, out: Path) -> int:
    from ..io import atomic_write
    from ..pipeline.photo_checks import list_photos
    from ..pipeline.ship_rule import format_ship_report, ship_decision, ship_figures

    missing = [o for o, given in (("--data", args.data), ("--clips", args.clips), ("--photos", args.photos))
               if not given]
    if missing:
        raise InputError(f"--ship: needs {', '.join(missing)} (stills, clips and photos to judge the models on)")
    unused = [o for o, given in (("--checkpoint", args.checkpoint), ("--light", args.light),
                                 ("--ablation", args.ablation), ("--as-photo", args.as_photo),
                                 ("--split", args.split != "test")) if given]
    if unused:
        raise InputError(f"{', '.join(unused)}: not used with --ship (it scores both models its own way)")
    if len(args.clips) != 1:
        raise InputError("--clips: --ship takes one clip dataset")
    list_photos(args.photos)
    models = [None if m == "shipped" else m for m in args.ship]
    for m in models:
        if m is not None and not Path(m).is_file():
            raise InputError(f"{m}: no such checkpoint (expected a .pt file or the word 'shipped')")
    figures = [ship_figures(m, args.data, args.clips[0], args.photos, device=args.device) for m in models]
    text = format_ship_report(*figures, names=tuple(args.ship))
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / "ship.md", "w") as f:
        f.write(f"# Ship rule: {args.ship[1]} against {args.ship[0]}\n\n{text}")
    with atomic_write(out / "ship.json", "w") as f:
        json.dump({"incumbent": args.ship[0], "candidate": args.ship[1], "figures": figures,
                   "decision": ship_decision(*figures)}, f, indent=2)
    logger.info("ship rule (%s):\n%s", out / "ship.md", text)
    return 0


def _evaluate_photos(args: argparse.Namespace, out: Path) -> int:
    from ..model.checkpoint import load_model
    from ..pipeline.photo_checks import format_photo_report, list_photos, photo_checks, write_photo_report

    unused = [o for o, given in (("--light", args.light), ("--clips", args.clips), ("--ablation", args.ablation),
                                 ("--no-baseline", args.no_baseline), ("--split", args.split != "test"),
                                 ("--as-photo", args.as_photo)) if given]
    if unused:
        raise InputError(f"{', '.join(unused)}: not used with --photos (the real-photo checks)")
    list_photos(args.photos)  # a missing folder, or one without photos, fails before the model loads
    model = load_model(args.checkpoint, device=args.device)
    name = str(args.checkpoint or "shipped model")
    result = photo_checks(model, args.photos)
    md, js = write_photo_report(result, out, name)
    print(format_photo_report(result, name))  # the command's own output (stdout), not a log message
    logger.info("wrote %s and %s", md, js)
    return 0


def run_estimate_light(args: argparse.Namespace) -> int:
    from ..checks import InputError
    from ..pipeline.backends import make_predictor
    from ..sh import save_light
    from ..sh.io import LIGHT_SUFFIXES
    from ..sh.plate import combine_person_plate, load_plate

    if args.image is None and args.plate is None:
        raise InputError("give a photo of a person (IMAGE), a background plate (--plate), or both")
    if args.fov is not None and args.plate is None:
        raise InputError("--fov is the plate's field of view: give --plate")
    out = out_file(args.out, suffixes=LIGHT_SUFFIXES)
    plate = None
    if args.plate is not None:
        plate = load_plate(args.plate, hfov_deg=args.fov or 60.0)
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
    p.add_argument("--device", default="cpu", help="cpu or cuda (default: cpu)")
    p.set_defaults(func=run_train, interrupt_hint=lambda a: f"run the same command with --resume to continue "
                   f"from {a.out}/last.pt")

    _register_evaluate(sub)

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
                   "(default: 60)")
    p.add_argument("--mask", help="mask of the person (white = person, or its alpha); default: the photo's alpha "
                   "if it has one, else the person segmentation (--mask-source)")
    add_mask_source_arg(p)
    p.add_argument("--out", required=True, help="light file: .npz/.json (ours) or .npy (Kanamori-Endo)")
    p.add_argument("--size", type=work_size, default=None,
                   help="working resolution, a multiple of 16 (default: the size the model was trained at)")
    add_model_args(p)
    p.set_defaults(func=run_estimate_light)


def _register_evaluate(sub) -> None:
    """The ``evaluate`` command's parser."""
    p = add_command(sub, "evaluate", "Evaluate a model on a dataset split against trivial baselines, or on real "
                    "photos of people (--photos); or the motion-capture fit (--fit) or the avatar capture "
                    "(--capture) on generated clips.",
                    "  relightnet evaluate --data data/synth --out reports/shipped\n"
                    "  relightnet evaluate --checkpoint runs/small/last.pt --data data/synth --split val --out r/\n"
                    "  relightnet evaluate --checkpoint runs/medium/last.pt --ablation runs/medium_unoccluded/last.pt "
                    "--data data/medium --out reports/ablation\n"
                    "  relightnet evaluate --light --data data/large --clips data/seq_constant data/seq_switch "
                    "--out reports/light\n"
                    "  relightnet evaluate --photos photos/ --out reports/photos_shipped\n"
                    "  relightnet evaluate --photos photos/ --checkpoint runs/large/last.pt --out reports/photos\n"
                    "  relightnet evaluate --fit --fit-clips 3 --fit-frames 12 --out reports/fit\n"
                    "  relightnet evaluate --capture --capture-clips 2 --capture-frames 48 --out reports/capture\n"
                    "  relightnet evaluate --ship shipped runs/next/last.pt --data data/clothed --clips data/seq_small "
                    "--photos photos/ --out reports/ship\n")
    add_model_args(p, backend=False)
    p.add_argument("--data", help="dataset folder made by 'relightnet synth' (or --photos)")
    p.add_argument("--photos", metavar="DIR",
                   help="the real-photo checks instead, on a folder of photos of people (no masks: the person "
                        "segmentation finds them): side contrast under a light from the left and from the right, "
                        "and the light's round trip through relighting and estimation (photo_checks.md, "
                        "photo_checks.json)")
    p.add_argument("--split", default="test", help="split (default: test: unseen bodies and unseen HDRIs)")
    p.add_argument("--out", default="out/evaluate", help="report folder: report.md, metrics.json, contact_sheet.png "
                   "(default: out/evaluate)")
    p.add_argument("--no-baseline", action="store_true", help="skip the mean-albedo/transport/light baseline")
    p.add_argument("--as-photo", action="store_true", help="score the items as photos: each composite framed "
                   "around its mask as relight-image frames a photo, the truth on the same box (default: the renders)")
    p.add_argument("--ablation", metavar="CHECKPOINT",
                   help="KE18's occlusion ablation: a twin trained on transport that ignores occlusion "
                        "(target: transport_unoccluded); adds relit RMSE overall and on concave pixels of both")
    p.add_argument("--light", action="store_true",
                   help="the light report instead: irradiance error by light family, direction and colour errors, "
                        "of the stills as rendered and as photos (each composite framed around its mask, as "
                        "relight-image frames a photo) (light_report.md, light_metrics.json)")
    p.add_argument("--clips", nargs="+", metavar="DATA",
                   help="with --light: clip datasets (clip_lights constant/switch) for drift and lag")
    p.add_argument("--fit", action="store_true",
                   help="the motion-capture report instead: 'relightnet fit' on generated test clips whose true "
                        "body is known (MPJPE, PA-MPJPE, 2D error, silhouette IoU, acceleration, foot skating, "
                        "time; fit_report.md, fit_metrics.json)")
    p.add_argument("--ship", nargs=2, metavar=("INCUMBENT", "CANDIDATE"),
                   help="the ship rule instead: both models (checkpoints, or 'shipped') scored on --data (as photos "
                        "and as rendered), --clips (compare) and --photos; the candidate ships when it keeps the "
                        "floors and lowers the mean relative light error (ship.md, ship.json)")
    p.add_argument("--capture", action="store_true",
                   help="the capture report instead: 'relightnet capture' of generated people turning under two "
                        "lights (albedo error, seen share, light invariance, silhouette IoU, a relit re-render in a "
                        "new pose, time, memory; capture_report.md, capture_metrics.json)")
    p.add_argument("--fit-clips", type=pos_int, default=3, help="with --fit: clips (default: 3)")
    p.add_argument("--fit-frames", type=pos_int, default=12, help="with --fit: frames per clip (default: 12)")
    p.add_argument("--fit-res", type=work_size, default=256, help="with --fit: clip size (default: 256)")
    p.add_argument("--capture-clips", type=pos_int, default=2, help="with --capture: people (default: 2)")
    p.add_argument("--capture-frames", type=pos_int, default=48, help="with --capture: frames per film (default: 48)")
    p.add_argument("--capture-res", type=work_size, default=256, help="with --capture: frame size (default: 256)")
    p.add_argument("--capture-texture", type=pos_int, default=512,
                   help="with --capture: texture side (default: 512)")
    p.set_defaults(func=run_evaluate)
