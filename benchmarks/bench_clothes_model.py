"""The shipped CNN on clothed people: transport and light errors per garment type, against painted people.

Run: ``.venv/bin/python benchmarks/bench_clothes_model.py [--n 96] [--painted 48]`` (ANNY_CACHE_DIR set by make).

The shipped model is named in its model card (trained on clothed people). Here the
generator (today's version, test split: held-out HDRIs, default garment draws, ``prt_reuse`` 1: one person each) makes
``--n`` stills at the model's 128², plus ``--painted`` stills of the same config with every
garment painted (``garment_probs`` all ``none``/``painted``) as the reference. The model
predicts albedo, transport and light from each image and mask; per sample: masked transport
RMSE (all K coefficients), light RMSE (all coefficients, RGB) and shading RMSE (T·L against the
truth). The table gives the mean per garment type (a sample counts in every type it wears)
and for the painted people; the gap is what training on clothed data has to close.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

from relightnet.data import SynthConfig, generate_samples
from relightnet.data.garments import GARMENT_TYPES
from relightnet.data.generate import (
    GENERATOR_VERSION,  # noqa: E402
    prepare_assets,  # noqa: E402
)
from relightnet.model.checkpoint import load_model  # noqa: E402
from relightnet.model.maps import shading_map  # noqa: E402
from relightnet.model.training import batch_to_input  # noqa: E402

_PAINTED = {"upper": {"none": 1}, "lower": {"none": 1}, "head": {"none": 1}, "hair": {"painted": 1}}


def _errors(model, samples) -> list[dict]:
    """Per-sample transport, light and shading RMSE of the model's prediction."""
    out = []
    for s in samples:
        a = {k: torch.from_numpy(v) for k, v in s.arrays.items()}
        b = {"image": a["image"].permute(2, 0, 1)[None], "mask": a["mask"][None, None]}
        with torch.no_grad():
            p = model(batch_to_input(b))
        M = b["mask"]
        T_gt = a["transport"].permute(2, 0, 1)[None]
        L_gt = a["light"][None]
        n = M.sum().clamp_min(1)
        t = float((((p.transport - T_gt) ** 2) * M).sum() / (n * T_gt.shape[1])) ** 0.5
        s_err = (shading_map(p.transport, p.light) - shading_map(T_gt, L_gt)) ** 2
        out.append({"types": s.meta["garments"]["types"], "transport": t,
                    "light": float(((p.light - L_gt) ** 2).mean()) ** 0.5,
                    "shading": float((s_err * M).sum() / (n * 3)) ** 0.5})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=96, help="clothed stills (default: 96)")
    ap.add_argument("--painted", type=int, default=48, help="painted stills (default: 48)")
    args = ap.parse_args()
    torch.set_num_threads(1)
    model = load_model().eval()
    assets = prepare_assets()
    clothed = _errors(model, generate_samples(SynthConfig(res=128, prt_reuse=1), "test", range(args.n), assets))
    painted = _errors(model, generate_samples(SynthConfig(res=128, prt_reuse=1, garment_probs=_PAINTED), "test",
                                              range(args.painted), assets))

    def row(name, errs):
        return [name, len(errs), *(statistics.mean(e[k] for e in errs) if errs else float("nan")
                                   for k in ("transport", "light", "shading"))]

    rows = [row("painted (garments as texture)", painted), row("clothed, all", clothed)]
    rows += [row(t, [e for e in clothed if t in e["types"]]) for t in GARMENT_TYPES]
    rows.append(row("clothed, none worn", [e for e in clothed if not e["types"]]))
    print(f"## The shipped CNN on generator version {GENERATOR_VERSION} (test split, 128², {os.cpu_count()} CPUs)\n")
    print(table(["people", "samples", "transport RMSE", "light RMSE", "shading RMSE"], rows))


if __name__ == "__main__":
    main()
