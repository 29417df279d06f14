"""Steady on video: the light of a shot (drift, switches, the facing leak), side by side with the sliding window.

Run: ``.venv/bin/python benchmarks/bench_steady.py --real ../shared/real-video [--turning 6]``.

``--real`` is a folder with ``turning.mp4`` (a person under a constant light) and its hand-made masks
``turning_masks.mkv``. The shipped model's per-frame estimates are computed once per clip, then smoothed
two ways: **window** — the evidence pooled over a sliding window of ``POOL_SECONDS`` inside segments split at
the switches found in the lights (what the video jobs did before); **shot** — what they do now
(:func:`relightnet.temporal.smooth_video_lights`: one light per segment unless its light changes, switches
also found in the frames' colour). Rows:

- the real clip with its hand-made masks and with the package's own segmentation: drift of the smoothed
  light (``evaluate light``'s definition: distance from the clip's mean over its level, p50/p90/max);
- the same clip with a light switch put in at frame ``--switch`` (every frame after it dimmed and warmed,
  in linear RGB, by ``--gain``): the switch frames found and the lag (frames until the estimate covers 90%
  of its own step);
- ``--turning`` generated people turning a full circle in place under a constant light
  (:func:`relightnet.capture.truth.turning_person`, 90 frames, exact masks): drift p90, the error against the
  true light (scale-invariant irradiance, median) and the correlation between the estimate's dominant
  direction and the person's facing (|Pearson| of the horizontal components, mean of the two; a constant
  estimate: 0).

The second table is ``relight-video`` (a preset light, the masks given) with the CNN's maps carried along
the optical flow (**carried**, the default) and without (**per frame**, ``--no-carry``):
:class:`relightnet.pipeline.flicker.FlickerMeter`'s added-flicker ratio (mean |relit_t − relit_{t−1}| over
mean |input_t − input_{t−1}| inside the person; 1.0: nothing added) and warp error (relit_t against
relit_{t−1} warped by the input's flow; the input's own beside it), frames per second of the whole job; and
``--relit`` generated people turning half a circle filmed under a warm key and relit to a cool one, where the
truth (the same person filmed under the cool key) is known: the truth's own ratio (what a perfect relight
scores: a person turning under a new light changes differently from the footage), the relit PSNR and the
temporal error against the truth (mean |(relit − truth)_t − (relit − truth)_{t−1}| inside the person, over the
frame pairs), medians.
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
from relightnet.temporal import light_distance, light_drift, pool_shot_lights
from relightnet.temporal.distance import light_norm
from relightnet.temporal.pooling import pool_window  # noqa: E402
from relightnet.temporal.registry import smooth_video_lights  # noqa: E402


def _smoothed(est, reg: float, fps: float) -> dict:
    """The two ways side by side: ``{"window": (T, K, 3), "shot": ...}`` and each one's switches."""
    window, _, window_sw = pool_shot_lights(est.evidence, est.prior, reg, window=pool_window(fps))
    shot = smooth_video_lights(est.raw, "pooled", est.evidence, est.prior, reg, fps, colour=est.colour)
    return {"window": window, "shot": shot.smoothed, "switches": {"window": window_sw, "shot": shot.switches}}


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
            d = light_drift(sm[way]).double()
            rows.append([f"real, constant light, {name}", way, f"{float(d.median()):.4f}",
                         f"{float(d.quantile(0.9)):.4f}", f"{float(d.max()):.4f}", "–", "–"])
    est = estimate_video_evidence(predict, _switched(video, work / "switched.mp4", at, gain), masks, progress=False)
    sm = _smoothed(est, predict.solve_reg, fps)
    for way in ("window", "shot"):
        lag = clip_metrics([{"raw": est.raw, "smoothed": sm[way], "switch": at}])["smoothed"]["lag_median"]
        rows.append([f"real, switch at frame {at} (×{gain})", way, "–", "–", "–",
                     str(sm["switches"][way].nonzero().flatten().tolist()), f"{lag:g}"])
    return rows


def _turning_rows(predict, n: int, work: Path) -> list:
    from relightnet.capture.truth import turning_person
    from relightnet.fit import FitBody
    from relightnet.light import ambient_light, directional_light

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
            err = light_distance(x, light.double()) / light_norm(light.double())
            per[way].append((float(light_drift(x).quantile(0.9)), float(err.median()), facing_correlation(x)))
    rows = []
    for way, v in per.items():
        a = np.array(v)
        rows.append([f"generated, turning a circle ({n} clips)", way, "–", f"{np.median(a[:, 0]):.4f}",
                     f"{a[:, 0].max():.4f}", f"error {np.median(a[:, 1]):.3f}",
                     f"facing corr. {np.median(a[:, 2]):.2f} (max {a[:, 2].max():.2f})"])
    return rows


def _meter(source, output, masks, truth=None) -> dict:
    """FlickerMeter of a relit video against its source; with ``truth`` (the person under the new light),
    also the relit PSNR and temporal error against it inside the masks."""
    from relightnet.io.video import read_video
    from relightnet.pipeline.flicker import FlickerMeter

    meter, se, n, terr, prev = FlickerMeter(), 0.0, 0, [], None
    streams = [read_video(source), read_video(output), read_video(masks)] + ([read_video(truth)] if truth else [])
    for frames in zip(*streams, strict=True):
        s, o, m = frames[0], frames[1], frames[2][..., 0] > 127
        meter.update(s, o, m)
        if truth:
            d = (o.astype(np.float64) - frames[3]) / 255
            se, n = se + float(np.square(d[m]).sum()), n + 3 * int(m.sum())
            if prev is not None:
                both = m & prev[2]
                terr.append(float(np.abs(d - prev[0])[both].mean()))
            prev = (d, None, m)
    out = meter.result()
    if truth:
        out.update(psnr=10 * math.log10(n / se), temporal_error=float(np.mean(terr)))
    return out


def _relit_rows(predict, real: Path, n_gen: int, work: Path) -> list:
    """relight-video (hand-made or exact masks, a preset light) with and without the carry along the flow."""
    import time

    from relightnet.capture.truth import light_pair, turning_person
    from relightnet.light.presets import preset_light
    from relightnet.pipeline.relight_video import relight_video

    rows = []
    video, masks = real / "turning.mp4", real / "turning_masks.mkv"
    for steady in (False, True):
        out = work / f"relit_{steady}.mp4"
        t0 = time.perf_counter()
        n = relight_video(predict, video, masks, preset_light("studio"), out, progress=False, steady=steady)
        fps = n / (time.perf_counter() - t0)
        m = _meter(video, out, masks)
        rows.append([f"real, hand-made masks, studio light ({n} frames)", "carried" if steady else "per frame",
                     f"{m['added_flicker']:.3f}", f"{m['warp_error']:.4f} ({m['source_warp_error']:.4f})", "–", "–",
                     f"{fps:.2f}"])
    if n_gen:
        from relightnet.fit import FitBody

        body, (a, b) = FitBody().body, light_pair()
        per = {"truth": [], False: [], True: []}
        for seed in range(1, n_gen + 1):
            src = turning_person(work / f"g{seed}a", body, a, n_frames=60, size=(320, 256), seed=seed, turns=0.5)
            tru = turning_person(work / f"g{seed}b", body, b, n_frames=60, size=(320, 256), seed=seed, turns=0.5)
            per["truth"].append(_meter(src.video, tru.video, src.masks))
            for steady in (False, True):
                out = work / f"g{seed}_{steady}.mp4"
                relight_video(predict, src.video, src.masks, b, out, progress=False, steady=steady)
                per[steady].append(_meter(src.video, out, src.masks, tru.video))
        for key, ms in per.items():
            med = {k: float(np.median([m[k] for m in ms])) for k in ms[0]}
            name = "truth (the person under the new light)" if key == "truth" else ("carried" if key else "per frame")
            rows.append([f"generated, half a turn, warm → cool key ({n_gen} clips)", name,
                         f"{med['added_flicker']:.3f}", f"{med['warp_error']:.4f} ({med['source_warp_error']:.4f})",
                         f"{med['psnr']:.2f}" if "psnr" in med else "–",
                         f"{med['temporal_error']:.4f}" if "temporal_error" in med else "–", "–"])
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--real", type=Path, required=True, help="folder with turning.mp4 and turning_masks.mkv")
    ap.add_argument("--turning", type=int, default=6, help="generated turning clips (0: none)")
    ap.add_argument("--switch", type=int, default=100, help="frame of the light switch put into the real clip")
    ap.add_argument("--gain", type=float, nargs=3, default=(0.75, 0.62, 0.45), help="the switch's linear RGB gain")
    ap.add_argument("--relit", type=int, default=3, help="generated clips relit with truth (0: none)")
    ap.add_argument("--only-relit", action="store_true", help="the relit table only")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args(argv)
    torch.set_num_threads(args.threads)
    predict = make_predictor("torch")
    with tempfile.TemporaryDirectory() as tmp:
        rows = [] if args.only_relit else _real_rows(predict, args.real, args.switch, tuple(args.gain), Path(tmp))
        if args.turning and not args.only_relit:
            rows += _turning_rows(predict, args.turning, Path(tmp))
        relit = _relit_rows(predict, args.real, args.relit, Path(tmp))
    print(f"CPU: {cpu_name()}, {args.threads} threads; the shipped model\n")
    if rows:
        print(table(["clip", "smoothing", "drift p50", "drift p90", "drift max", "switches found / error",
                     "lag (frames) / facing"], rows) + "\n")
    print(table(["clip", "maps", "added flicker", "warp error (source's)", "PSNR vs truth (dB)",
                 "temporal error vs truth", "frames/s"], relit))


if __name__ == "__main__":
    main()
