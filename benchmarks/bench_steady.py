"""Steady on video: the light of a shot (drift, switches, the facing leak), side by side with the sliding window.

Run: ``.venv/bin/python benchmarks/bench_steady.py --real ../shared/real-video [--turning 6]``.

``--real`` is a folder with ``turning.mp4`` (a person under a constant light) and its hand-made masks
``turning_masks.mkv``. The shipped model's per-frame estimates are computed once per clip, then smoothed
two ways: **window** — the evidence pooled over a sliding window of ``POOL_SECONDS`` inside segments split at
the switches found in the lights (what the video jobs did before); **shot** — what they do now
(:func:`relightnet.temporal.smooth_video_lights`: one light per segment unless its light changes, switches
also found in the frames' colour). Rows:

- the real clip with its hand-made masks and with the package's own segmentation: drift of the smoothed
  light (``evaluate --light``'s definition: distance from the clip's mean over its level, p50/p90/max);
- the same clip with a light switch put in at frame ``--switch`` (every frame after it dimmed and warmed,
  in linear RGB, by ``--gain``): the switch frames found and the lag (frames until the estimate covers 90%
  of its own step);
- ``--turning`` generated people turning a full circle in place under a constant light
  (:func:`relightnet.capture.turning_person`, 90 frames, exact masks): drift p90, the error against the
  true light (scale-invariant irradiance, median) and the correlation between the estimate's dominant
  direction and the person's facing (|Pearson| of the horizontal components, mean of the two; a constant
  estimate: 0).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import cpu_name, table  # noqa: E402

from relightnet.pipeline.backends import make_predictor  # noqa: E402
from relightnet.pipeline.light_eval import clip_metrics  # noqa: E402
from relightnet.pipeline.video_lights import estimate_video_evidence  # noqa: E402
from relightnet.sh.metrics import dominant_direction  # noqa: E402
from relightnet.temporal import light_distance, light_norm, pool_shot_lights, pool_window  # noqa: E402
from relightnet.temporal.registry import smooth_video_lights  # noqa: E402


def _smoothed(est, reg: float, fps: float) -> dict:
    """The two ways side by side: ``{"window": (T, K, 3), "shot": ...}`` and the shot's switches."""
    window, _, _ = pool_shot_lights(est.evidence, est.prior, reg, window=pool_window(fps))
    shot = smooth_video_lights(est.raw, "pooled", est.evidence, est.prior, reg, fps, colour=est.colour)
    return {"window": window, "shot": shot.smoothed, "switches": shot.switches}


def _switched(video: Path, out: Path, at: int, gain) -> Path:
    """``video`` with every frame from ``at`` on times ``gain`` in linear RGB (a light dimmed and recoloured)."""
    from relightnet.color import linear_to_srgb, srgb_to_linear
    from relightnet.io import VideoWriter, video_info
    from relightnet.io.video import read_video

    g = torch.tensor(gain, dtype=torch.float32)
    with VideoWriter(out, fps=video_info(video).fps) as w:
        for t, fr in enumerate(read_video(video)):
            x = torch.from_numpy(fr).float() / 255
            if t >= at:
                x = linear_to_srgb((srgb_to_linear(x) * g).clamp(0, 1))
            w.write((x * 255).round().to(torch.uint8).numpy())
    return out


def facing_correlation(est: torch.Tensor) -> float:
    """|Pearson| between the dominant direction's (x, z) and the facing (sin θ, cos θ) of a person turning
    one circle over the clip (θ = 2π t / T), mean of the two; 0 for a constant estimate."""
    d = dominant_direction(est.double())
    th = 2 * math.pi * torch.arange(est.shape[0], dtype=torch.float64) / est.shape[0]
    out = []
    for a, b in ((d[:, 0], torch.sin(th)), (d[:, 2], torch.cos(th))):
        out.append(0.0 if float(a.std()) < 1e-9 else abs(float(torch.corrcoef(torch.stack([a, b]))[0, 1])))
    return float(np.mean(out))


def _real_rows(predict, real: Path, at: int, gain, work: Path) -> list:
    video, masks = real / "turning.mp4", real / "turning_masks.mkv"
    rows = []
    fps = 30.0
    for name, m in (("hand-made masks", masks), ("own segmentation", None)):
        est = estimate_video_evidence(predict, video, m, progress=False)
        sm = _smoothed(est, predict.solve_reg, fps)
        for way in ("window", "shot"):
            d = clip_metrics([{"raw": est.raw, "smoothed": sm[way], "switch": None}])["smoothed"]
            drift = _drift_max(sm[way])
            rows.append([f"real, constant light, {name}", way, f"{d['drift_p50']:.4f}", f"{d['drift_p90']:.4f}",
                         f"{drift:.4f}", "–", "–"])
    est = estimate_video_evidence(predict, _switched(video, work / "switched.mp4", at, gain), masks, progress=False)
    sm = _smoothed(est, predict.solve_reg, fps)
    window_sw = pool_shot_lights(est.evidence, est.prior, predict.solve_reg, window=pool_window(fps))[2]
    for way, sw in (("window", window_sw), ("shot", sm["switches"])):
        lag = clip_metrics([{"raw": est.raw, "smoothed": sm[way], "switch": at}])["smoothed"]["lag_median"]
        rows.append([f"real, switch at frame {at} (×{gain})", way, "–", "–", "–",
                     str(sw.nonzero().flatten().tolist()), f"{lag:g}"])
    return rows


def _drift_max(lights: torch.Tensor) -> float:
    mean = lights.mean(0, keepdim=True)
    return float((light_distance(lights, mean) / light_norm(mean).clamp_min(1e-12)).max())


def _turning_rows(predict, n: int, work: Path) -> list:
    from relightnet.capture.truth import turning_person
    from relightnet.fit import FitBody
    from relightnet.sh import ambient_light, directional_light

    body, rng = FitBody().body, np.random.default_rng(7)
    per = {"raw": [], "window": [], "shot": []}
    for i in range(n):
        d = rng.normal(size=3)
        d[1], d[2] = abs(d[1]) * 0.5, abs(d[2])
        light = ambient_light(float(rng.uniform(0.2, 0.5))) + directional_light(
            torch.tensor(d, dtype=torch.float32), 2.0 * torch.tensor(0.7 + 0.3 * rng.random(3), dtype=torch.float32))
        clip = turning_person(work / f"turn{i}", body, light, n_frames=90, size=(320, 256), seed=100 + i)
        est = estimate_video_evidence(predict, clip.video, clip.masks, progress=False)
        sm = {"raw": est.raw, **_smoothed(est, predict.solve_reg, 30.0)}
        for way in per:
            x = sm[way].double()
            mean = x.mean(0, keepdim=True)
            err = light_distance(x, light.double()) / light_norm(light.double())
            per[way].append((float((light_distance(x, mean) / light_norm(mean)).quantile(0.9)), float(err.median()),
                             facing_correlation(x)))
    rows = []
    for way, v in per.items():
        a = np.array(v)
        rows.append([f"generated, turning a circle ({n} clips)", way, "–", f"{np.median(a[:, 0]):.4f}",
                     f"{a[:, 0].max():.4f}", f"error {np.median(a[:, 1]):.3f}",
                     f"facing corr. {np.median(a[:, 2]):.2f} (max {a[:, 2].max():.2f})"])
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--real", type=Path, required=True, help="folder with turning.mp4 and turning_masks.mkv")
    ap.add_argument("--turning", type=int, default=6, help="generated turning clips (0: none)")
    ap.add_argument("--switch", type=int, default=100, help="frame of the light switch put into the real clip")
    ap.add_argument("--gain", type=float, nargs=3, default=(0.75, 0.62, 0.45), help="the switch's linear RGB gain")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args(argv)
    torch.set_num_threads(args.threads)
    predict = make_predictor("torch")
    with tempfile.TemporaryDirectory() as tmp:
        rows = _real_rows(predict, args.real, args.switch, tuple(args.gain), Path(tmp))
        if args.turning:
            rows += _turning_rows(predict, args.turning, Path(tmp))
    print(f"CPU: {cpu_name()}, {args.threads} threads; the shipped model\n")
    print(table(["clip", "smoothing", "drift p50", "drift p90", "drift max", "switches found / error",
                 "lag (frames) / facing"], rows))


if __name__ == "__main__":
    main()
