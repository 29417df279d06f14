"""``relightnet compare``: the 2D baseline vs the 3D path on generated clips with ground truth (pipeline job 4)."""

from __future__ import annotations

import argparse
import logging

from ..names import VIDEO_SMOOTHING, smoothing_help
from .argtypes import nonneg_int, pos_int, work_size
from .options import add_command, add_model_args
from .paths import in_path, out_dir

logger = logging.getLogger("relightnet.compare")


def run(args: argparse.Namespace) -> int:
    from ..pipeline.compare import compare
    from ..pipeline.settings import PredictorSettings
    from ..prt import PrtSettings

    in_path(args.data, "--data", "a dataset folder of clips made by 'relightnet synth --sequence T'")
    predictor = PredictorSettings(checkpoint=args.checkpoint, backend=args.backend, device=args.device, size=args.size)
    prt = PrtSettings(n_dirs=args.n_dirs, seed=args.prt_seed, bounces=args.bounces)
    res = compare(args.data, out_dir(args.out), predictor=predictor, split=args.split, clips=args.clips, prt=prt,
                  smoothing=args.smoothing, progress=not args.quiet, source=args.source_light,
                  cnn_albedo=args.cnn_albedo)
    s = res.metrics["summary"]["rows"]
    best = {(r["path"], r["light"]): r["rmse"] for r in s}
    logger.info("smoothed light: RMSE 2D %.4f, 3D %.4f (true light: 2D %.4f, 3D %.4f)", best[("2d", "smoothed")],
                best[("3d", "smoothed")], best[("2d", "true")], best[("3d", "true")])
    logger.info("report: %s", res.out_dir / "report.md")
    return 0


def register(sub) -> None:
    p = add_command(sub, "compare",
                    "Compare the 2D path (CNN transport) and the 3D path (mesh PRT), each under the true, the "
                    "estimated and the smoothed light, on generated clips with ground truth; writes report.md, "
                    "metrics.json, plots and a side-by-side video.",
                    "  relightnet synth --config train/configs/seq_small.yaml --out data/seq_small --workers 2\n"
                    "  relightnet compare --data data/seq_small --out reports/compare\n"
                    "  relightnet compare --data data/seq_small --checkpoint runs/small/last.pt --clips 2 "
                    "--smoothing poly --out reports/compare_poly\n"
                    "  relightnet compare --data data/seq_small --backend onnx --n-dirs 128 "
                    "--out reports/compare_onnx\n")
    p.add_argument("--data", required=True, metavar="SEQ_DIR",
                   help="a dataset of clips made by 'relightnet synth --sequence T' (or sequence_frames > 0)")
    p.add_argument("--out", required=True, metavar="REPORT_DIR",
                   help="report folder (made if needed; nothing is written there unless the run succeeds)")
    p.add_argument("--split", default="test", choices=("train", "val", "test"),
                   help="split to use (default: %(default)s)")
    p.add_argument("--clips", type=pos_int, metavar="N", help="only the first N clips (default: all)")
    p.add_argument("--n-dirs", type=pos_int, default=64, help="PRT directions of the 3D path (default: %(default)s)")
    p.add_argument("--prt-seed", type=nonneg_int, default=0,
                   help="rotation seed of the 3D path's PRT directions (default: %(default)s)")
    p.add_argument("--bounces", type=nonneg_int, default=0,
                   help="interreflection bounces of the 3D path (default: %(default)s)")
    p.add_argument("--smoothing", default="auto", choices=VIDEO_SMOOTHING,
                   help=smoothing_help(VIDEO_SMOOTHING, "auto"))
    p.add_argument("--source-light", default="studio", metavar="PRESET",
                   help="preset light of the 2D path's input image of the subject (default: %(default)s)")
    p.add_argument("--size", type=work_size, help="CNN working size, a multiple of 16 (default: its training size)")
    p.add_argument("--cnn-albedo", action="store_true",
                   help="the 2D path relights the CNN's albedo (default: the photo divided by the predicted "
                        "shading, as relight-video does)")
    add_model_args(p)
    p.set_defaults(func=run)
