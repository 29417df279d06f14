"""``relightnet evaluate data|light|photos|fit|capture|ship``: the reports on the CNN, the fit and the capture."""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from ..errors import InputError
from .argtypes import pos_int, work_size
from .options import add_command, add_model_args, no_subcommand
from .paths import out_dir

logger = logging.getLogger("relightnet.model")

#: Sizes of the generated test clips of ``evaluate fit`` and ``evaluate capture``.
FIT_CLIPS, FIT_FRAMES, FIT_RES = 3, 12, 256
CAPTURE_CLIPS, CAPTURE_FRAMES, CAPTURE_RES, CAPTURE_TEXTURE = 2, 48, 256, 512


def run_data(args: argparse.Namespace) -> int:
    from ..io import atomic_write
    from ..model.checkpoint import load_model
    from ..model.evaluate import baseline_from_train, evaluate, format_ablation, format_table, write_report

    out = out_dir(args.out)
    model = load_model(args.checkpoint, device=args.device)
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


def run_light(args: argparse.Namespace) -> int:
    from ..io import atomic_write
    from ..model.checkpoint import load_model
    from ..pipeline.light_eval import evaluate_light, format_light_report

    out = out_dir(args.out)
    model = load_model(args.checkpoint, device=args.device)
    result = evaluate_light(model, args.data, clips=args.clips or (), split=args.split)
    text = format_light_report(result, str(args.checkpoint or "shipped model"))
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / "light_report.md", "w") as f:
        f.write(f"# Light estimation: {args.checkpoint or 'shipped model'} on {args.data}\n\n{text}")
    with atomic_write(out / "light_metrics.json", "w") as f:
        json.dump(result, f, indent=2)
    logger.info("light report (%s):\n%s", out / "light_report.md", text)
    return 0


def run_photos(args: argparse.Namespace) -> int:
    from ..model.checkpoint import load_model
    from ..pipeline.photo_checks import format_photo_report, list_photos, photo_checks, write_photo_report

    out = out_dir(args.out)
    list_photos(args.photos)  # a missing folder, or one without photos, fails before the model loads
    model = load_model(args.checkpoint, device=args.device)
    name = str(args.checkpoint or "shipped model")
    result = photo_checks(model, args.photos)
    md, js = write_photo_report(result, out, name)
    print(format_photo_report(result, name))  # the command's own output (stdout), not a log message
    logger.info("wrote %s and %s", md, js)
    return 0


def run_fit(args: argparse.Namespace) -> int:
    from ..io import atomic_write
    from ..pipeline.fit_eval import evaluate_fit, format_fit_report

    out = out_dir(args.out)
    result = evaluate_fit(args.clips, args.frames, args.res,
                          progress=lambda i, r: logger.info("clip %d (%s): MPJPE %.1f mm, IoU %.3f", i, r["motion"],
                                                            r["mpjpe"], r["iou_body"]))
    text = format_fit_report(result)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / "fit_report.md", "w") as f:
        f.write(f"# Fitting Anny: {args.clips} generated test clips of {args.frames} frames at "
                f"{args.res}²\n\n{text}\n")
    with atomic_write(out / "fit_metrics.json", "w") as f:
        json.dump(result, f, indent=2)
    print(text)  # the command's own output (stdout), not a log message
    return 0


def run_capture(args: argparse.Namespace) -> int:
    from ..pipeline.backends import make_predictor
    from ..pipeline.capture_eval import evaluate_capture, format_capture_report

    out = out_dir(args.out)
    predictor = make_predictor("torch", args.checkpoint, args.device)
    result = evaluate_capture(predictor, out, args.clips, args.frames, args.res, args.texture,
                              progress=lambda i, r: logger.info("clip %d (seed %d): albedo RMSE %.3f, IoU %.3f, "
                                                                "re-render %.1f dB", i, r["seed"], r["albedo_rmse"],
                                                                r["iou_offset"], r["psnr"]))
    print(format_capture_report(result))  # the command's own output (stdout), not a log message
    logger.info("wrote %s and %s", out / "capture_report.md", out / "capture_metrics.json")
    return 0


def run_ship(args: argparse.Namespace) -> int:
    from ..io import atomic_write
    from ..pipeline.photo_checks import list_photos
    from ..pipeline.ship_rule import format_ship_report, ship_decision, ship_figures

    out = out_dir(args.out)
    list_photos(args.photos)
    names = (args.incumbent, args.candidate)
    models = [None if m == "shipped" else m for m in names]
    for m in models:
        if m is not None and not Path(m).is_file():
            raise InputError(f"{m}: no such checkpoint (expected a .pt file or the word 'shipped')")
    figures = [ship_figures(m, args.data, args.clips, args.photos, device=args.device) for m in models]
    text = format_ship_report(*figures, names=names)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / "ship.md", "w") as f:
        f.write(f"# Ship rule: {names[1]} against {names[0]}\n\n{text}")
    with atomic_write(out / "ship.json", "w") as f:
        json.dump({"incumbent": names[0], "candidate": names[1], "figures": figures,
                   "decision": ship_decision(*figures)}, f, indent=2)
    logger.info("ship rule (%s):\n%s", out / "ship.md", text)
    return 0


def _out_arg(p: argparse.ArgumentParser, files: str) -> None:
    p.add_argument("--out", default="out/evaluate", help=f"report folder: {files} (default: %(default)s)")


def _data_args(p: argparse.ArgumentParser) -> None:
    """--data and --split: the dataset of stills a report scores."""
    p.add_argument("--data", required=True, help="dataset folder made by 'relightnet synth'")
    p.add_argument("--split", default="test", help="split (default: %(default)s: unseen bodies and unseen HDRIs)")


def _register_data(esub) -> None:
    p = add_command(esub, "data", "Score a model on a dataset split made by 'relightnet synth' against trivial "
                    "baselines: albedo, transport, light and relit errors, a contact sheet.",
                    "  relightnet evaluate data --data data/synth --out reports/shipped\n"
                    "  relightnet evaluate data --checkpoint runs/small/last.pt --data data/synth --split val "
                    "--out r/\n"
                    "  relightnet evaluate data --as-photo --no-baseline --data data/clothed --out reports/photo\n"
                    "  relightnet evaluate data --checkpoint runs/small/last.pt --ablation "
                    "runs/small_unoccluded/last.pt --data data/small --out reports/ablation\n")
    add_model_args(p, backend=False)
    _data_args(p)
    _out_arg(p, "report.md, metrics.json, contact_sheet.png")
    p.add_argument("--no-baseline", action="store_true", help="skip the mean-albedo/transport/light baseline")
    p.add_argument("--as-photo", action="store_true", help="score the items as photos: each composite framed "
                   "around its mask as relight-image frames a photo, the truth on the same box (default: the renders)")
    p.add_argument("--ablation", metavar="CHECKPOINT",
                   help="KE18's occlusion ablation: a twin trained on transport that ignores occlusion "
                        "(target: transport_unoccluded); adds relit RMSE overall and on concave pixels of both")
    p.set_defaults(func=run_data)


def _register_light(esub) -> None:
    p = add_command(esub, "light", "The light report: irradiance error by light family, direction and colour "
                    "errors, of the stills as rendered and as photos (each composite framed around its mask, as "
                    "relight-image frames a photo); with --clips, drift and lag over time.",
                    "  relightnet evaluate light --data data/clothed --clips data/seq_constant data/seq_switch "
                    "--out reports/light\n"
                    "  relightnet evaluate light --checkpoint runs/small/last.pt --data data/synth --out r/\n")
    add_model_args(p, backend=False)
    _data_args(p)
    _out_arg(p, "light_report.md, light_metrics.json")
    p.add_argument("--clips", nargs="+", metavar="DATA",
                   help="clip datasets (clip_lights constant/switch) for drift and lag")
    p.set_defaults(func=run_light)


def _register_photos(esub) -> None:
    p = add_command(esub, "photos", "The real-photo checks, on a folder of photos of people (no masks: the person "
                    "segmentation finds them): side contrast under a light from the left and from the right, and "
                    "the light's round trip through relighting and estimation.",
                    "  relightnet evaluate photos photos/ --out reports/photos_shipped\n"
                    "  relightnet evaluate photos photos/ --checkpoint runs/small/last.pt --out reports/photos\n")
    p.add_argument("photos", metavar="DIR", help="folder of photos of people")
    add_model_args(p, backend=False)
    _out_arg(p, "photo_checks.md, photo_checks.json")
    p.set_defaults(func=run_photos)


def _register_fit(esub) -> None:
    p = add_command(esub, "fit", "The motion-capture report: 'relightnet fit' on generated test clips whose true "
                    "body is known (MPJPE, PA-MPJPE, 2D error, silhouette IoU, acceleration, foot skating, time).",
                    "  relightnet evaluate fit --out reports/fit\n"
                    "  relightnet evaluate fit --clips 3 --frames 12 --res 256 --out reports/fit\n")
    _out_arg(p, "fit_report.md, fit_metrics.json")
    _generated_args(p, (FIT_CLIPS, FIT_FRAMES, FIT_RES), ("generated clips", "frames per clip", "clip size"))
    p.set_defaults(func=run_fit)


def _generated_args(p, defaults: tuple[int, int, int], what: tuple[str, str, str]) -> None:
    """``--clips``, ``--frames`` and ``--res`` of a report on generated clips: their defaults and their words."""
    for flag, kind, default, words in zip(("--clips", "--frames", "--res"), (pos_int, pos_int, work_size), defaults,
                                          what, strict=True):
        p.add_argument(flag, type=kind, default=default, help=f"{words} (default: %(default)s)")


def _register_capture(esub) -> None:
    p = add_command(esub, "capture", "The capture report: 'relightnet capture' of generated people turning under "
                    "two lights (albedo error, seen share, light invariance, silhouette IoU, a relit re-render in a "
                    "new pose, time, memory).",
                    "  relightnet evaluate capture --out reports/capture\n"
                    "  relightnet evaluate capture --clips 2 --frames 48 --out reports/capture\n")
    add_model_args(p, backend=False)
    _out_arg(p, "capture_report.md, capture_metrics.json")
    _generated_args(p, (CAPTURE_CLIPS, CAPTURE_FRAMES, CAPTURE_RES), ("generated people", "frames per film",
                                                                      "frame size"))
    p.add_argument("--texture", type=pos_int, default=CAPTURE_TEXTURE, help="texture side (default: %(default)s)")
    p.set_defaults(func=run_capture)


def _register_ship(esub) -> None:
    p = add_command(esub, "ship", "The ship rule: both models scored on --data (as photos and as rendered), "
                    "--clips (compare) and --photos; the candidate ships when it keeps the floors and lowers the "
                    "mean relative light error.",
                    "  relightnet evaluate ship shipped runs/next/last.pt --data data/clothed --clips data/seq_small "
                    "--photos photos/ --out reports/ship\n")
    p.add_argument("incumbent", metavar="INCUMBENT", help="the model shipped now: a checkpoint or 'shipped'")
    p.add_argument("candidate", metavar="CANDIDATE", help="the model that would replace it: a checkpoint or 'shipped'")
    p.add_argument("--data", required=True, help="dataset of stills made by 'relightnet synth' (its test split)")
    p.add_argument("--clips", required=True, metavar="DATA", help="a clip dataset (compare on its clips)")
    p.add_argument("--photos", required=True, metavar="DIR", help="folder of photos of people")
    p.add_argument("--device", default="cpu", help="cpu or cuda (default: %(default)s)")
    _out_arg(p, "ship.md, ship.json")
    p.set_defaults(func=run_ship)


def register(sub) -> None:
    """Add ``evaluate`` and its reports to ``sub``."""
    p = add_command(sub, "evaluate", "Evaluate: a model on a dataset split (data), its light (light), the 2D path on "
                    "real photos (photos), the motion-capture fit (fit) or the avatar capture (capture) on generated "
                    "clips, or the ship rule between two models (ship).",
                    "  relightnet evaluate data --data data/synth --out reports/shipped\n"
                    "  relightnet evaluate light --data data/clothed --clips data/seq_constant data/seq_switch "
                    "--out reports/light\n"
                    "  relightnet evaluate photos photos/ --out reports/photos_shipped\n"
                    "  relightnet evaluate fit --clips 3 --frames 12 --out reports/fit\n"
                    "  relightnet evaluate capture --clips 2 --frames 48 --out reports/capture\n"
                    "  relightnet evaluate ship shipped runs/next/last.pt --data data/clothed --clips data/seq_small "
                    "--photos photos/ --out reports/ship\n")
    p.set_defaults(func=no_subcommand(p))
    esub = p.add_subparsers(dest="report", metavar="{data,light,photos,fit,capture,ship}")
    for add in (_register_data, _register_light, _register_photos, _register_fit, _register_capture, _register_ship):
        add(esub)
