"""Job 4 of the pipeline: the 2D-baseline comparison on generated clips with exact ground truth.

The task is the relighting step of motion transfer: render a subject under the light of a
target video, a light that has to be estimated from that video. Every clip of a sequence
dataset (``relightnet synth --sequence T``) is one such case, made by
:func:`relightnet.data.generate_sequence`: the subject moves, the light turns, ramps and may
switch, and the clip stores the truth — ``image`` = albedo ⊙ (transport · L_t), linear, zero
outside ``mask``. Per clip:

1. **Light.** The CNN estimates L̂_t from each target frame (``image_composite``, the person
   over a background, 8-bit sRGB) with its mask; L̃_t =
   :func:`~relightnet.temporal.smooth_lights` (L̂, method, outlier_eps="3mad",
   switches="auto"), as ``relightnet avatar`` does (:func:`~relightnet.temporal.smooth_video_lights`):
   by default one light solve per shot for a network that solves its light (``pooled``), else
   the robust Hermite spline (``smoothing="none"``, or fewer than 3 frames: L̃ = L̂).
2. **2D path** (the baseline, Kanamori–Endo style). The CNN sees the subject in a "texture
   photo" under a fixed *source* light: I_src,t = albedo_t ⊙ (transport_t · L_src), exact from
   the clip's stored albedo and transport, L_src the ``studio`` preset scaled to level 1
   (:func:`source_light`), 8-bit sRGB. It predicts Â_t, T̂_t and L̂_src; output = Â_t ⊙ (T̂_t · L)
   with Â_t the photo's albedo I_src,t / (T̂_t · L̂_src) as ``relight-video`` relights
   (:func:`~relightnet.model.photo_albedo`), or the CNN's own albedo (``cnn_albedo``).
3. **3D path.** The clip's own mesh (:func:`relightnet.data.render_sample.clip_geometry`:
   the same body, motion, camera and albedo texture), per-vertex transport by our PRT
   (:func:`relightnet.prt.vertex_transport`, occlusion, ``n_dirs`` directions rotated by
   ``prt_seed`` — not the ground truth's directions), rasterized with the clip's camera:
   output = A ⊙ (T · L).

Each path is shaded with L ∈ {true L_t, raw L̂_t, smoothed L̃_t}: six outputs, compared with
the ground truth ``image`` in its mask, on sRGB-encoded values (clipped to [0, 1], then
:func:`~relightnet.color.linear_to_srgb`) with :mod:`relightnet.pipeline.metrics`: RMSE,
PSNR, SSIM per frame, and the temporal error per pair of frames. No exposure matching: the
lights of the data are on an absolute scale. The light error (irradiance L2,
:func:`~relightnet.temporal.light_error`) compares L̂ and L̃ with the truth.

Aggregates: per clip, the mean over its frames (PSNR: mean of the per-frame dB values) and
the temporal error pooled over its frame pairs; over the run, the mean over all frames of
all clips, and the mean of the clips' temporal and light errors. The report's files are
described in :mod:`relightnet.pipeline.compare_report`; one clip's stages are in
:mod:`relightnet.pipeline.compare_clip`.
"""

from __future__ import annotations

import logging
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, check_device
from ..names import VIDEO_SMOOTHING
from ..prt import PrtSettings
from ..temporal.registry import check_smoothing
from ..threads import torch_threads
from .compare_clip import (
    CLIP_FIELDS,
    CLIP_FPS,
    LIGHTS,
    PATHS,
    ClipOutputs,
    clip_metrics,
    compare_clip,
    source_light,
)
from .settings import PredictorSettings

logger = logging.getLogger(__name__)


__all__ = ["PATHS", "LIGHTS", "CLIP_FIELDS", "ClipOutputs", "CompareResult", "source_light",
           "compare_clip", "clip_metrics", "compare"]


@dataclass(frozen=True)
class CompareResult:
    """What :func:`compare` returns: the report folder, the files written (name → path), and the
    numbers (the content of ``metrics.json``)."""

    out_dir: Path
    files: dict
    metrics: dict


def _open_data(data_dir, split: str):
    """The dataset's config and its listed shard files of ``split``; InputError for anything unusable."""
    from ..data.config import SPLITS
    from ..data.shards import dataset_config, load_manifest

    if split not in SPLITS:
        raise InputError(f"split: expected one of {', '.join(SPLITS)}, got {split!r}")
    root = Path(data_dir)
    manifest = load_manifest(root)
    try:
        cfg = dataset_config(manifest)
        entries = sorted(manifest["splits"].get(split, {}).get("shards", []), key=lambda e: e["index"])
        files = [(root / e["file"], int(e["count"])) for e in entries]
    except (KeyError, TypeError, AttributeError) as e:
        raise InputError(f"{root}: bad manifest ({type(e).__name__}: {e})") from None
    if not cfg.sequence_frames:
        raise InputError(f"{root}: a dataset of still samples (sequence_frames = 0), not of clips; make clips "
                         "with 'relightnet synth --sequence T'")
    n_planned = int(manifest["splits"].get(split, {}).get("n_shards", len(files)))
    if files and len(files) < n_planned:
        logger.warning("%s: %d of %d shards of %s are made; comparing their clips", root, len(files), n_planned, split)
    if not files:
        planned = int(cfg.counts.get(split, 0))
        raise InputError(f"{root}: split {split!r} has no clips" + (" made yet" if planned else ""))
    return cfg, files


def _clips(files, n: int | None):
    """Yield (meta, arrays) of the first ``n`` clips (all with None), one shard in memory at a time."""
    from ..data.shards import read_shard

    done = 0
    for path, _ in files:
        arrays = read_shard(path, (*CLIP_FIELDS, "meta"))
        for j, meta in enumerate(arrays["meta"]):
            if n is not None and done >= n:
                return
            yield meta, {k: arrays[k][j] for k in CLIP_FIELDS}
            done += 1


def _one_thread_geometry(cfg, split, index, T, assets):
    """:func:`clip_geometry` single-threaded, as the generator ran (bit-identical mesh and mask)."""
    from ..data.render_sample import clip_geometry

    with torch_threads(1):
        return clip_geometry(cfg, split, index, T, assets)


def _check_options(smoothing, n_dirs, clips, bounces, source) -> None:
    """Every option of :func:`compare` checked before any work (InputError naming it; the CNN's size:
    :class:`~relightnet.pipeline.PredictorSettings`)."""
    from ..light import preset_names

    check_smoothing(smoothing, VIDEO_SMOOTHING)
    for name, v, lo in (("n_dirs", n_dirs, 1), ("clips", clips, 1), ("bounces", bounces, 0)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < lo):
            raise InputError(f"{name}: expected an integer >= {lo}, got {v!r}")
    if source not in preset_names():
        raise InputError(f"source: expected a preset name ({', '.join(preset_names())}), got {source!r}")


def _clip_record(index: int, meta: dict, clip: dict, out: ClipOutputs) -> dict:
    """The numbers of one clip with what the data says about it (its switches, light source, bounce)."""
    mask = torch.from_numpy(np.asarray(clip["mask"], np.float32))
    rec = {"index": index, **clip_metrics(out, torch.from_numpy(np.asarray(clip["image"])), mask),
           "switch_frames": list(meta.get("switch_frames", [])),
           "light_source": str(meta.get("light", {}).get("source", "?")),
           "bounce": bool(meta.get("flags", {}).get("bounce", False))}
    if rec["mask_iou_3d"] < 0.99:
        logger.warning("clip %d: the 3D path's mask differs from the clip's (IoU %.3f): was the data made "
                       "by another generator or body-model version?", index, rec["mask_iou_3d"])
    return rec


def _run_clips(stage: Path, predictor, cfg, files, split, clips, assets, opts: dict, progress: bool):
    """Both paths on every clip, each clip added to the staged report as it is done:
    returns (records, light arrays, seconds per stage)."""
    from tqdm import tqdm

    from ..io import VideoWriter
    from . import compare_report as R

    T = cfg.sequence_frames
    n_total = sum(c for _, c in files) if clips is None else min(clips, sum(c for _, c in files))
    records, light_arrays = [], {}
    secs = {"cnn": 0.0, "prt": 0.0, "render": 0.0}
    with (tqdm(total=n_total * T, unit="frame", desc="compare", disable=not progress, dynamic_ncols=True) as bar,
          VideoWriter(stage / "side_by_side.mp4", fps=CLIP_FPS) as video):
        for meta, clip in _clips(files, clips):
            index = int(meta["seed"]["index"])
            geo = _one_thread_geometry(cfg, split, index, T, assets)
            out = compare_clip(predictor, clip, geo, tick=lambda: bar.update(1), **opts)
            for k in secs:
                secs[k] += out.seconds[k]
            rec = _clip_record(index, meta, clip, out)
            records.append(rec)
            R.add_clip(stage, video, clip, out, rec, light_arrays)
    return records, light_arrays, secs


def _write_report(stage: Path, records, light_arrays, settings: dict, secs: dict, total: float, T: int) -> dict:
    """metrics.json, lights.npz, report.md and the summary plots into the staged report: returns the metrics."""
    from . import compare_report as R

    R.plot_summary(stage / "plots" / "errors.png", stage / "plots" / "light_error.png", records)
    frames = len(records) * T
    metrics = {
        "format": "relightnet-compare/1",
        "settings": {"data": settings["data"], "split": settings["split"], "clips": [r["index"] for r in records],
                     **{k: v for k, v in settings.items() if k not in ("data", "split")}},
        "timing": {"frames": frames, "total_s": total, "frames_per_s": frames / total,
                   **{f"{k}_s": v for k, v in secs.items()}},
        "summary": R.summarize(records),
        "clips": records,
    }
    R.write_json(stage / "metrics.json", metrics)
    R.write_lights(stage / "lights.npz", light_arrays)
    with (stage / "report.md").open("w", encoding="utf-8") as f:
        f.write(R.format_report(metrics))
    return metrics


@torch.no_grad()
def compare(data_dir, out_dir, predictor: PredictorSettings = PredictorSettings(), split: str = "test",
            clips: int | None = None, prt: PrtSettings = PrtSettings(n_dirs=64), smoothing: str = "auto",
            progress: bool = True, source: str = "studio", body=None, cnn_albedo: bool = False) -> CompareResult:
    """Compare the 2D and 3D paths on the clips of a sequence dataset and write a report (module docstring).

    Args:
        data_dir: a dataset folder made by ``relightnet synth`` with ``sequence_frames > 0``.
        out_dir: the report folder (made if needed; the files of an earlier report are replaced).
            Everything is made in a hidden folder beside it and moved in at the end, so a failed
            run leaves nothing.
        predictor: the CNN (:class:`~relightnet.pipeline.PredictorSettings`: its checkpoint, default the
            shipped model, or with ``backend="onnx"`` also an ``.onnx`` file, exported once,
            :func:`~relightnet.pipeline.backends.make_predictor`; the device, ``"cpu"`` or ``"cuda"``,
            PRT and rasterization run on the CPU; the working size, default its training size).
        split: which split's clips.
        clips: the first N clips (default: all).
        prt: the 3D path's PRT (:class:`~relightnet.prt.PrtSettings`: directions, their rotation seed,
            interreflections; by default 64 directions).
        smoothing: one of :data:`relightnet.names.VIDEO_SMOOTHING` (default ``auto``: ``pooled`` for a
            network that solves its light, else ``hermite``).
        progress: show a tqdm bar (frames/s).
        source: preset name of the 2D path's source light.
        body: an :class:`~relightnet.body.AnnyBody` or ``SynthAssets`` to reuse (default: a new one).
        cnn_albedo: the 2D path relights the CNN's albedo (default: the photo's, as relight-video).

    Returns:
        :class:`CompareResult`.

    Raises:
        InputError: a missing or unusable dataset, an empty split, a bad checkpoint or option.
    """
    from ..data.sample import assets_for
    from ..model.checkpoint import shipped_checkpoint
    from . import compare_report as R
    from .backends import make_predictor

    t_start = time.perf_counter()
    n_dirs, prt_seed, bounces, checkpoint = prt.n_dirs, prt.seed, prt.bounces, predictor.checkpoint
    _check_options(smoothing, n_dirs, clips, bounces, source)
    dev = check_device(predictor.device, "device")
    cfg, files = _open_data(data_dir, split)
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"{out_dir}: exists and is not a folder")
    backend = predictor.backend
    predictor = make_predictor(backend, checkpoint, str(dev), size=predictor.size)
    assets = assets_for(body)
    settings = {"data": str(Path(data_dir)), "split": split,
                "checkpoint": str(shipped_checkpoint() if checkpoint is None else Path(checkpoint)),
                "backend": backend, "size": predictor.size, "device": str(dev), "smoothing": smoothing,
                "smoothing_options": {"outlier_eps": "3mad", "switches": "auto"}, "n_dirs": n_dirs,
                "prt_seed": prt_seed, "bounces": bounces, "source_light": source, "source_level": 1.0,
                "albedo_2d": "cnn" if cnn_albedo else "photo", "dataset": cfg.to_dict()}
    opts = {"prt": prt, "smoothing": smoothing, "source": source, "cnn_albedo": cnn_albedo}
    stage = R.staging_dir(out_dir)
    try:
        (stage / "plots").mkdir()
        records, light_arrays, secs = _run_clips(stage, predictor, cfg, files, split, clips, assets, opts, progress)
        total = time.perf_counter() - t_start
        metrics = _write_report(stage, records, light_arrays, settings, secs, total, cfg.sequence_frames)
        files_out = R.publish(stage, out_dir)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    logger.info("wrote %s (%d clips, %d frames, %.1f s)", out_dir, len(records), metrics["timing"]["frames"], total)
    return CompareResult(out_dir, files_out, metrics)
