"""Which of two models ships: floors plus one score (``relightnet evaluate ship INCUMBENT CANDIDATE``).

A candidate replaces the shipped model when it keeps every floor and improves the score:

- **floors**: the real-photo side contrast through the user's path (:mod:`.photo_checks`: the
  package's own masks) at least :data:`SIDE_CONTRAST_FLOOR`; and no generated-data metric of
  :data:`FLOOR_METRICS` more than :data:`WORSE_BY` (5%) worse than the incumbent's. Those are the
  test split's maps and relit images *as photos*: each composite framed around its mask as
  ``relight-image`` frames a photo (``evaluate data --as-photo``), the only framing a user's input has.
  The same metrics on the renders at their training framing are reported beside them
  (:data:`INFO_METRICS`) but do not block;
- **score**: the mean over :data:`SCORE_METRICS` of the candidate's light error divided by the
  incumbent's (so each error counts by its relative change): the test split's stills as photos
  (median scale-invariant irradiance error, ``evaluate light``), ``relightnet compare`` on clips
  (mean relative error of the per-frame estimate) and the real-photo round trip through the user's
  path (median over photos × lights). Below 1 is better.

:func:`ship_figures` measures one model; :func:`ship_decision` applies the rule to two models' figures.
"""

from __future__ import annotations

import statistics
import tempfile
from pathlib import Path

__all__ = ["SIDE_CONTRAST_FLOOR", "WORSE_BY", "FLOOR_METRICS", "SCORE_METRICS", "INFO_METRICS", "ship_figures",
           "ship_decision", "format_ship_report"]

#: The least real-photo side contrast a shipped model may have.
SIDE_CONTRAST_FLOOR = 4.0
#: How much worse than the incumbent's a floor metric may be (relative).
WORSE_BY = 0.05
#: Generated-data floor metrics (as photos): name → True where higher is better.
FLOOR_METRICS = {"transport_rmse_as_photos": False, "albedo_rmse_as_photos": False, "shading_rmse_as_photos": False,
                 "relit_psnr_as_photos": True, "relit_rmse_photo_albedo_as_photos": False}
#: The light errors whose relative change is averaged into the score (lower is better).
SCORE_METRICS = ("light_error_as_photos", "compare_light_error", "photo_round_trip")
#: Reported, not ruled on: name → True where higher is better.
INFO_METRICS = {"light_error_as_rendered": False, "transport_rmse_as_rendered": False,
                "shading_rmse_as_rendered": False, "relit_psnr_as_rendered": True,
                "photo_chroma_shift_p99": False, "photo_fine_chroma_ratio": False}
_MAPS = ("transport_rmse", "albedo_rmse", "shading_rmse", "relit_psnr", "relit_rmse_photo_albedo")


def ship_figures(model, data, clips, photos, device: str = "cpu") -> dict:
    """Every figure the rule reads, for one model.

    Args:
        model: a checkpoint path, or None for the shipped model.
        data: a dataset of stills (``relightnet synth``) with a test split.
        clips: a dataset of clips (``sequence_frames`` > 0) for ``compare``.
        photos: a folder of photos of people (no masks).
        device: torch device.

    Returns:
        name → float, the keys of :data:`FLOOR_METRICS`, :data:`SCORE_METRICS`, :data:`INFO_METRICS`
        and ``photo_side_contrast``.
    """
    from ..model.checkpoint import load_model
    from ..model.evaluate import evaluate
    from .compare import compare
    from .light_eval import split_lights, still_metrics
    from .photo_checks import photo_checks
    from .settings import PredictorSettings

    net = load_model(model, device=device)
    out: dict = {}
    for how, photo in (("as_photos", True), ("as_rendered", False)):
        maps = evaluate(net, data, split="test", photo=photo)["model"]
        out |= {f"{k}_{how}": float(maps[k]) for k in _MAPS}
        est, true, sources = split_lights(net, data, "test", photo=photo)
        out[f"light_error_{how}"] = float(still_metrics(est, true, sources)["all"]["error"]["median"])
    with tempfile.TemporaryDirectory(prefix=".relightnet-ship-") as tmp:
        summary = compare(clips, Path(tmp) / "compare", predictor=PredictorSettings(checkpoint=model, device=device),
                          progress=False).metrics["summary"]
    out["compare_light_error"] = float(summary["light"]["raw"]["relative"])
    checks = photo_checks(model, photos, device=device)["median"]
    out |= {"photo_round_trip": checks["round_trip"], "photo_side_contrast": checks["side_contrast"],
            "photo_chroma_shift_p99": checks["chroma_shift_p99"],
            "photo_fine_chroma_ratio": checks["fine_chroma_ratio"]}
    return out


def _worse(inc: float, cand: float, higher_better: bool) -> float:
    """How much worse ``cand`` is than ``inc`` (relative; negative when better)."""
    return (inc - cand) / abs(inc) if higher_better else (cand - inc) / abs(inc)


def ship_decision(incumbent: dict, candidate: dict) -> dict:
    """The rule (module docstring) on two models' :func:`ship_figures`.

    Returns:
        ``{"ships": bool, "score": float, "floors": {name: {"worse", "ok"}}, "side_contrast_ok": bool,
        "reasons": [str]}``: ``score`` the mean relative light error (< 1 improves), ``worse`` each floor
        metric's relative change (positive is worse), ``reasons`` why the candidate does not ship.
    """
    floors = {k: {"worse": _worse(incumbent[k], candidate[k], hb)} for k, hb in FLOOR_METRICS.items()}
    for f in floors.values():
        f["ok"] = f["worse"] <= WORSE_BY
    score = statistics.fmean(candidate[k] / incumbent[k] for k in SCORE_METRICS)
    side_ok = candidate["photo_side_contrast"] >= SIDE_CONTRAST_FLOOR
    reasons = [f"{k} {100 * f['worse']:.1f}% worse (floor {100 * WORSE_BY:.0f}%)" for k, f in floors.items()
               if not f["ok"]]
    if not side_ok:
        reasons.append(f"side contrast {candidate['photo_side_contrast']:.2f} < {SIDE_CONTRAST_FLOOR}")
    if score >= 1:
        reasons.append(f"score {score:.3f}: the light errors do not improve")
    return {"ships": not reasons, "score": score, "floors": floors, "side_contrast_ok": side_ok, "reasons": reasons}


def format_ship_report(incumbent: dict, candidate: dict, names: tuple[str, str] = ("incumbent", "candidate")) -> str:
    """A markdown table of both models' figures and the rule's verdict."""
    d = ship_decision(incumbent, candidate)
    lines = [f"| figure | role | {names[0]} | {names[1]} | change |", "|---|---|---|---|---|"]
    rows = [(k, "score") for k in SCORE_METRICS] + [("photo_side_contrast", f"floor ≥ {SIDE_CONTRAST_FLOOR:g}")]
    rows += [(k, f"floor ≤ +{100 * WORSE_BY:.0f}%") for k in FLOOR_METRICS] + [(k, "reported") for k in INFO_METRICS]
    higher = FLOOR_METRICS | INFO_METRICS | {"photo_side_contrast": True}
    for k, role in rows:
        change = -_worse(incumbent[k], candidate[k], higher.get(k, False))
        lines.append(f"| {k} | {role} | {incumbent[k]:.4f} | {candidate[k]:.4f} | {100 * change:+.1f}% better |"
                     if change >= 0 else
                     f"| {k} | {role} | {incumbent[k]:.4f} | {candidate[k]:.4f} | {100 * -change:.1f}% worse |")
    verdict = "ships" if d["ships"] else "does not ship: " + "; ".join(d["reasons"])
    lines += ["", f"Score (mean of the candidate's light errors ÷ the incumbent's): {d['score']:.3f}. "
              f"The candidate {verdict}."]
    return "\n".join(lines) + "\n"
