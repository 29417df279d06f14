"""The offline pooling window (``POOL_SECONDS``): drift, switch lag and the cost on a changing light, side by side.

Run: ``.venv/bin/python benchmarks/bench_pooling.py --constant data/seq_constant --switch data/seq_switch
--turning data/seq_turning [--checkpoint shipped] [--seconds 0.5 1 2 3]`` (clip datasets made from
``train/configs/seq_{constant,switch,turning}.yaml``).

Each clip's per-frame evidence is computed once (the CNN), then pooled with every window
(:func:`relightnet.temporal.pool_shot_lights`, switches detected as the jobs do). Columns:

- drift p50/p90 of the constant clips (``evaluate light``'s definition), lag median/max of the switch clips;
- the turning clips' scale-invariant light error (median, p90) of the pooled estimate, as the jobs get it;
- "window cost": the same window applied to the clips' *true* per-frame lights (true switches), against the
  truth: what the window alone costs a light that turns (up to 60°/s), i.e. the error a perfect per-frame
  estimator would get after pooling.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

from relightnet.data.dataset import SynthDataset  # noqa: E402
from relightnet.model.checkpoint import load_model  # noqa: E402
from relightnet.pipeline.backends import as_predictor  # noqa: E402
from relightnet.pipeline.light_eval import clip_metrics  # noqa: E402
from relightnet.sh.light_solve import stack_evidence  # noqa: E402
from relightnet.sh.metrics import scale_invariant_light_error  # noqa: E402
from relightnet.temporal.pooling import pool_shot_lights, pool_window, pooling_weights  # noqa: E402


def _clips(predict, data_dir) -> list[dict]:
    ds = SynthDataset(data_dir, "test", fields=("image_composite", "mask", "light"), cache_shards=1)
    out = []
    for i in range(len(ds)):
        it, meta = ds[i], ds.meta(i)
        meta = json.loads(meta) if isinstance(meta, str) else meta
        lights, evs, priors = [], [], []
        for t in range(it["light"].shape[0]):
            light, ev, prior = predict.light_evidence(it["image_composite"][t], it["mask"][t, 0])
            lights.append(light.float())
            evs.append(ev)
            priors.append(prior)
        ev, prior = stack_evidence(evs, priors)
        switches = meta.get("switch_frames") or []
        out.append({"raw": torch.stack(lights), "ev": ev, "prior": prior, "true": it["light"].double(),
                    "switch": int(switches[0]) if switches else None, "fps": float(meta.get("fps", 30.0))})
    return out


def _pooled(clips, seconds, reg) -> list[dict]:
    return [{**c, "smoothed": pool_shot_lights(c["ev"], c["prior"], reg, window=pool_window(c["fps"], seconds))[0]}
            for c in clips]


def _window_cost(clips, seconds) -> torch.Tensor:
    errs = []
    for c in clips:
        true = c["true"]
        switches = torch.zeros(true.shape[0], dtype=torch.bool)
        if c["switch"] is not None:
            switches[c["switch"]] = True
        w = pooling_weights(switches, pool_window(c["fps"], seconds))
        pooled = (w @ true.flatten(1) / w.sum(1, keepdim=True)).view_as(true)
        errs.append(scale_invariant_light_error(pooled, true))
    return torch.cat(errs)


def _q(x: torch.Tensor) -> tuple[float, float]:
    return float(x.median()), float(torch.quantile(x.double(), 0.9))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--constant", required=True)
    ap.add_argument("--switch", required=True)
    ap.add_argument("--turning", required=True)
    ap.add_argument("--checkpoint", default="shipped")
    ap.add_argument("--seconds", type=float, nargs="+", default=[0.5, 1.0, 2.0, 3.0])
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    predict = as_predictor(load_model(None if args.checkpoint == "shipped" else args.checkpoint).eval())
    fixed = _clips(predict, args.constant) + _clips(predict, args.switch)
    turning = _clips(predict, args.turning)
    rows = []
    for s in args.seconds:
        pooled = _pooled(fixed, s, predict.solve_reg)
        m = clip_metrics([{k: c[k] for k in ("raw", "smoothed", "switch")} for c in pooled])
        m = m["smoothed"]
        err = torch.cat([scale_invariant_light_error(c["smoothed"].double(), c["true"])
                         for c in _pooled(turning, s, predict.solve_reg)])
        rows.append([s, m["drift_p50"], m["drift_p90"], m["lag_median"], m["lag_max"], *_q(err),
                     *_q(_window_cost(turning, s))])
    raw = torch.cat([scale_invariant_light_error(c["raw"].double(), c["true"]) for c in turning])
    rows.append(["per frame", "", "", "", "", *_q(raw), 0.0, 0.0])
    print(table(["pool seconds", "drift p50", "drift p90", "lag median", "lag max", "turning error median",
                 "turning error p90", "window cost median", "window cost p90"], rows))


if __name__ == "__main__":
    main()
