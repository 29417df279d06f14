"""How good the estimated light is: per photo (by light family) and per shot (drift, lag).

``relightnet evaluate light`` runs :func:`evaluate_light`:

- **stills** — every item of a split (the test split: unseen bodies, the held-out env maps
  rotated and new procedural lights), seen two ways: as rendered (the person alone at the
  generator's own framing, what training sees) and **as a photo** (the item's composite over its
  background, framed around its mask by :func:`~relightnet.model.inference.estimate_light`, the
  path of ``relight-image`` and the video jobs); grouped by the light's source (:data:`LIGHT_SOURCES`):
  the scale-invariant irradiance error over the whole sphere and over the camera-facing
  hemisphere, the angle between the dominant directions and the chromaticity error
  (:mod:`relightnet.sh.metrics`), medians and 90th percentiles, beside a direction-less
  light of the true colour (the truth's l = 0 band alone);
- **clips** — datasets of clips made with ``clip_lights: constant`` or ``switch``: the drift of a
  constant light, ``‖E_t − Ē‖ / ‖Ē‖`` (irradiance over the sphere, Ē the clip's mean estimate),
  p50 and p90 over frames, per-frame and after the video pooling; and for a switch, the lag:
  frames after the switch until the estimate has covered 90% of its own step (the plateaus
  before and after the switch).
"""

from __future__ import annotations

import json
import math

import numpy as np
import torch

from ..checks import InputError
from ..data.lights import LIGHT_SOURCES
from ..sh.light_solve import stack_evidence
from ..sh.metrics import chromaticity_error, direction_error, scale_invariant_light_error
from ..temporal.metrics import light_drift

__all__ = ["split_lights", "still_metrics", "clip_lights", "clip_metrics", "evaluate_light", "format_light_report"]


def _sources(ds) -> list[str]:
    metas = (ds.meta(i) for i in range(len(ds)))
    return [(json.loads(m) if isinstance(m, str) else m)["light"]["source"] for m in metas]


@torch.no_grad()
def split_lights(model, data_dir, split: str = "test", batch: int = 16, photo: bool = False):
    """Estimated and true lights of a split's stills.

    Args:
        model: a :class:`~relightnet.model.RelightNet` (eval mode), run at the data's size.
        data_dir: a dataset folder (``relightnet synth``) of stills.
        split: which split.
        batch: items per forward pass.
        photo: estimate from each item's composite framed as a photo
            (:func:`~relightnet.model.inference.estimate_light` with the item's mask), one item
            at a time; else from the render at its own framing.

    Returns:
        ``(est (N, K, 3), true (N, K, 3), sources: list of N source names)``.
    """
    from ..data.dataset import SynthDataset
    from ..model.inference import estimate_light
    from ..model.training import batch_to_input

    fields = ("image_composite", "mask", "light") if photo else ("image", "mask", "light")
    ds = SynthDataset(data_dir, split, fields=fields, cache_shards=1)
    if ds.sequence:
        raise InputError(f"{data_dir}: a dataset of clips; give one of stills (the clips go to --clips)")
    if len(ds) == 0:
        raise InputError(f"{data_dir}: the {split} split is empty")
    dev = next(model.parameters()).device
    est, true = [], []
    if photo:
        for i in range(len(ds)):
            it = ds[i]
            est.append(estimate_light(model, it["image_composite"].to(dev), it["mask"][0].to(dev)).float().cpu()[None])
            true.append(it["light"][None])
        return torch.cat(est), torch.cat(true), _sources(ds)
    for s in range(0, len(ds), batch):
        items = [ds[i] for i in range(s, min(s + batch, len(ds)))]
        b = {k: torch.stack([it[k] for it in items]).to(dev) for k in ("image", "mask", "light")}
        est.append(model(batch_to_input(b)).light.float().cpu())
        true.append(b["light"].cpu())
    return torch.cat(est), torch.cat(true), _sources(ds)


def _stats(x: torch.Tensor) -> dict:
    x = x.double()
    return {"median": float(x.median()), "p90": float(torch.quantile(x, 0.9)), "mean": float(x.mean())}


def still_metrics(est: torch.Tensor, true: torch.Tensor, sources: list[str]) -> dict:
    """Per-family and overall statistics of the still metrics (module docstring).

    Args:
        est, true: (N, K, 3) lights. sources: N source names.

    Returns:
        ``{group: {"n", "error", "error_hemisphere", "direction_deg", "chromaticity", "ambient_error"}}``,
        each metric a dict of median/p90/mean; groups are the sources present and ``"all"``.
    """
    ambient = torch.zeros_like(true)
    ambient[:, 0] = true[:, 0]
    per = {"error": scale_invariant_light_error(est.double(), true),
           "error_hemisphere": scale_invariant_light_error(est, true, hemisphere=True),
           "direction_deg": direction_error(est, true), "chromaticity": chromaticity_error(est, true),
           "ambient_error": scale_invariant_light_error(ambient.double(), true)}
    src = np.array(sources)
    out = {}
    for group in [*(s for s in LIGHT_SOURCES if s in set(sources)), "all"]:
        sel = torch.from_numpy(src == group) if group != "all" else torch.ones(len(src), dtype=torch.bool)
        out[group] = {"n": int(sel.sum()), **{k: _stats(v[sel]) for k, v in per.items()}}
    return out


@torch.no_grad()
def clip_lights(predictor, data_dir, split: str = "test", smoothing: str = "auto") -> list[dict]:
    """Per-frame and pooled/smoothed light estimates of every clip of a clip dataset.

    Args:
        predictor: a model or predictor (:mod:`relightnet.pipeline.backends`).
        data_dir: a dataset of clips (``sequence_frames`` > 0).
        split: which split.
        smoothing: as the video jobs (:data:`relightnet.names.VIDEO_SMOOTHING`).

    Returns:
        One dict per clip: ``raw``, ``smoothed`` (T, K, 3), ``true`` (T, K, 3), ``switch`` (the
        first frame of the new light, or None).
    """
    from ..data.dataset import SynthDataset
    from ..temporal.registry import smooth_video_lights
    from ..temporal.switches import frame_colour
    from .backends import as_predictor

    predict = as_predictor(predictor)
    ds = SynthDataset(data_dir, split, fields=("image_composite", "mask", "light"), cache_shards=1)
    if not ds.sequence:
        raise InputError(f"{data_dir}: not a dataset of clips (make one with sequence_frames > 0)")
    out = []
    for i in range(len(ds)):
        it, meta = ds[i], ds.meta(i)
        meta = json.loads(meta) if isinstance(meta, str) else meta
        lights, evs, priors = [], [], []
        for t in range(it["light"].shape[0]):
            light, ev, prior = predict.light_evidence(it["image_composite"][t], it["mask"][t, 0])
            lights.append(light.float().cpu())
            evs.append(ev)
            priors.append(prior)
        raw = torch.stack(lights)
        ev, prior = stack_evidence(evs, priors)
        colour = torch.stack([frame_colour(x) for x in it["image_composite"]])
        smoothed = smooth_video_lights(raw, smoothing, ev, prior, predict.solve_reg, meta.get("fps", 30.0),
                                       colour=colour)[0]
        switches = meta.get("switch_frames") or []
        out.append({"raw": raw, "smoothed": smoothed, "true": it["light"].float(),
                    "switch": int(switches[0]) if switches else None})
    return out


def _own_lag(est: torch.Tensor, step: int, plateau: int = 4) -> float:
    """Frames after ``step`` until ``est`` covers 90% of its own step (plateau means before/after)."""
    from ..temporal.metrics import step_lag

    before = est[max(0, step - plateau):step].mean(0)
    after = est[-plateau:].mean(0)
    levels = torch.stack([before if t < step else after for t in range(est.shape[0])])
    if float((after - before).abs().sum()) == 0:
        return math.inf
    return float(step_lag(est, levels, step))


def clip_metrics(clips: list[dict]) -> dict:
    """Drift (constant clips) and lag (switch clips) of :func:`clip_lights`'s output, raw and smoothed."""
    res = {}
    for key in ("raw", "smoothed"):
        const = [light_drift(c[key]) for c in clips if c["switch"] is None]
        lags = [_own_lag(c[key], c["switch"]) for c in clips if c["switch"] is not None]
        entry = {"clips_constant": len(const), "clips_switch": len(lags)}
        if const:
            d = torch.cat(const)
            entry["drift_p50"], entry["drift_p90"] = float(d.median()), float(torch.quantile(d.double(), 0.9))
        if lags:
            entry["lag_median"], entry["lag_max"] = float(np.median(lags)), float(max(lags))
        res[key] = entry
    return res


def evaluate_light(model, data_dir=None, clips=(), split: str = "test", smoothing: str = "auto") -> dict:
    """The light report: still metrics of ``data_dir`` and clip metrics of each ``clips`` dataset."""
    result: dict = {}
    if data_dir is not None:
        est, true, sources = split_lights(model, data_dir, split)
        result["stills"] = still_metrics(est, true, sources)
        est, true, sources = split_lights(model, data_dir, split, photo=True)
        result["stills_photo"] = still_metrics(est, true, sources)
    if clips:
        every = [c for d in clips for c in clip_lights(model, d, split, smoothing)]
        result["clips"] = clip_metrics(every)
    if not result:
        raise InputError("evaluate light: give a dataset of stills (--data) or of clips (--clips)")
    return result


def format_light_report(result: dict, name: str = "model") -> str:
    """Markdown tables of :func:`evaluate_light`'s result."""
    lines = []
    for key, how in (("stills", "as rendered"), ("stills_photo", "as photos: the composite, framed around its mask")):
        if key not in result:
            continue
        lines += [""] if lines else []
        lines += [f"Stills {how} ({name}): scale-invariant irradiance error (sphere / camera "
                  "hemisphere), dominant-direction angle, chromaticity error; median (p90). Ambient: a direction-less "
                  "light of the true colour.", "",
                  "| lights | n | error | error, hemisphere | direction ° | chromaticity | ambient error |",
                  "|---|---|---|---|---|---|---|"]
        for g, m in result[key].items():
            cells = [f"{m[k]['median']:.3f} ({m[k]['p90']:.3f})" for k in ("error", "error_hemisphere")]
            cells += [f"{m['direction_deg']['median']:.1f} ({m['direction_deg']['p90']:.1f})",
                      f"{m['chromaticity']['median']:.3f} ({m['chromaticity']['p90']:.3f})",
                      f"{m['ambient_error']['median']:.3f}"]
            lines.append(f"| {g} | {m['n']} | " + " | ".join(cells) + " |")
    if "clips" in result:
        lines += ["", f"Clips ({name}): drift of a constant light (p50 / p90 over frames) and frames to follow a "
                  "switch (median / max).", "", "| estimate | drift p50 | drift p90 | lag median | lag max |",
                  "|---|---|---|---|---|"]
        for key, m in result["clips"].items():
            cells = [f"{m[k]:.3f}" if k in m else "–" for k in ("drift_p50", "drift_p90")]
            cells += [f"{m[k]:.0f}" if k in m else "–" for k in ("lag_median", "lag_max")]
            lines.append(f"| {key} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
