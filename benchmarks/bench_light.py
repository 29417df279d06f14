"""Light estimation quality of several models side by side, in one run.

Run: ``.venv/bin/python benchmarks/bench_light.py --data data/clothed --clips data/seq_constant data/seq_switch
--checkpoints shipped train/checkpoints/clothed_photo_side_masks.pt [--out reports/light_bench.md]``

For every model: the still metrics of ``relightnet evaluate light`` per light family, of the test items as
rendered and as photos (their composites framed around their masks by the package's own path): median and p90 of the
scale-invariant irradiance error over the sphere and the camera hemisphere, dominant-direction angle,
chromaticity error) and, with ``--clips``, drift p50/p90 of constant lights and the lag after a switch, per
frame and after the video pooling/smoothing the jobs use (``auto``).
"""

from __future__ import annotations

import argparse
import os
import sys

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

from relightnet.model.checkpoint import load_model  # noqa: E402
from relightnet.pipeline.light_eval import evaluate_light  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True, help="dataset of stills (its test split)")
    ap.add_argument("--clips", nargs="*", default=[], help="clip datasets (clip_lights constant/switch)")
    ap.add_argument("--checkpoints", nargs="+", default=["shipped"], help="'shipped' or checkpoint paths")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", help="also write the tables to this markdown file")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    results = {}
    for c in args.checkpoints:
        model = load_model(None if c == "shipped" else c).eval()
        results[c] = evaluate_light(model, args.data, clips=args.clips)
    rows = []
    for c, res in results.items():
        for key, how in (("stills", "render"), ("stills_photo", "photo")):
            for g, m in res[key].items():
                rows.append([c, how, g, m["n"], m["error"]["median"], m["error"]["p90"],
                             m["error_hemisphere"]["median"], m["direction_deg"]["median"], m["chromaticity"]["median"],
                             m["ambient_error"]["median"]])
    text = table(["model", "input", "lights", "n", "error median", "error p90", "hemisphere median",
                  "direction ° median", "chromaticity median", "ambient error median"], rows)
    if args.clips:
        crow = []
        for c, res in results.items():
            for key, m in res["clips"].items():
                crow.append([c, key, *(m.get(k, float("nan")) for k in ("drift_p50", "drift_p90", "lag_median",
                                                                       "lag_max"))])
        text += "\n\n" + table(["model", "estimate", "drift p50", "drift p90", "lag median", "lag max"], crow)
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
