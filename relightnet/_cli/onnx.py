"""``relightnet export`` (ONNX with the smoothing layer) and ``relightnet onnx-run`` (ONNX Runtime serving)."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from ..names import STREAMING_SMOOTHING, smoothing_help
from .argtypes import work_size
from .options import add_command, add_model_args, check_method_options, method_options
from .paths import in_path, out_dir, out_file

logger = logging.getLogger("relightnet.onnx")


def run_export(args: argparse.Namespace) -> int:
    from ..model.checkpoint import load_checkpoint, load_model, shipped_checkpoint
    from ..model.onnx_export import export_onnx
    from ..temporal.registry import resolve_smoothing

    out = out_file(args.out, suffixes=(".onnx",))
    ckpt = Path(in_path(args.checkpoint, "--checkpoint")) if args.checkpoint else shipped_checkpoint()
    if args.smoothing != "auto":  # refused before the model loads
        check_method_options(args, args.smoothing)
    net = load_model(ckpt)
    smoothing = resolve_smoothing(args.smoothing, net.solves, causal=True)
    check_method_options(args, smoothing)
    opts = {"alpha": args.alpha} if smoothing == "ema" else {}
    out = export_onnx(net, out, smoothing=smoothing,
                      train_config=load_checkpoint(ckpt).get("train_config"), **opts)
    if args.int8:
        from ..model.onnx_serving import quantize_int8

        q = quantize_int8(out, out.with_name(out.stem + "_int8.onnx"), mode=args.int8_mode,
                          reduce_range=args.int8_weight_bits == 7)
        logger.info("wrote %s (int8, %s quantisation)", q, args.int8_mode)
    return 0


def run_onnx(args: argparse.Namespace) -> int:
    from ..model.onnx_serving import run_video

    in_path(args.model, "MODEL")
    in_path(args.video, "--video")
    if args.masks:
        in_path(args.masks, "--masks")
    out = out_dir(args.out_dir, "--out-dir")
    res = run_video(args.model, args.video, args.masks, out, size=args.size)
    logger.info("wrote %d frames of lights (raw and smoothed) and albedo.mp4 to %s", len(res["raw"]), args.out_dir)
    return 0


def register(sub) -> None:
    p = add_command(sub, "export", "Export the CNN with a streaming light-smoothing layer to one ONNX file.",
                    "  relightnet export --out relightnet.onnx\n"
                    "  relightnet export --checkpoint runs/small/last.pt --out m.onnx --smoothing one-euro\n"
                    "  relightnet export --out m.onnx --int8          # also writes m_int8.onnx\n")
    add_model_args(p, backend=False, device=False)
    p.add_argument("--out", required=True, help="output .onnx (weights inside)")
    p.add_argument("--smoothing", choices=STREAMING_SMOOTHING, default="auto",
                   help=smoothing_help(STREAMING_SMOOTHING, "auto") + "; inside the graph")
    p.add_argument("--alpha", type=float, default=0.3, help="ema: weight of the newest frame (default: %(default)g)")
    method_options(p, {"alpha": ("ema",)})
    p.add_argument("--int8", action="store_true", help="also write OUT_int8.onnx")
    p.add_argument("--int8-mode", choices=("static", "dynamic"), default="static",
                   help="static: QDQ int8 convolutions calibrated on 16 generated people (default); "
                   "dynamic: int8 weights only")
    p.add_argument("--int8-weight-bits", type=int, choices=(7, 8), default=7,
                   help="static int8 weights: 7 bits (default, right on every x86 CPU) or 8 (for CPUs with VNNI/AMX "
                        "int8 instructions: closer to fp32 there, saturating elsewhere)")
    p.set_defaults(func=run_export)

    p = add_command(sub, "onnx-run", "Run an exported model over a video with ONNX Runtime (lights per frame).",
                    "  relightnet onnx-run relightnet.onnx --video clip.mp4 --out-dir out/clip  # masks: segmentation\n"
                    "  relightnet onnx-run relightnet.onnx --video clip.mp4 --masks masks/ --out-dir out/clip\n"
                    "  relightnet onnx-run m.onnx --video clip.mp4 --masks clip_masks.mp4 --out-dir out/clip\n")
    p.add_argument("model", help="model from 'relightnet export'")
    p.add_argument("--video", required=True, help="input video (mp4, mkv, ...)")
    p.add_argument("--masks", help="folder of per-frame mask images (sorted) or a mask video (default: the person "
                   "segmentation, tracked from frame to frame)")
    p.add_argument("--out-dir", required=True, help="output folder: lights_raw.npz, lights_smoothed.npz, albedo.mp4")
    p.add_argument("--size", type=work_size, default=None, help="working size (default: the model's training size)")
    p.set_defaults(func=run_onnx)
