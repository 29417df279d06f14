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
   switches="auto"), as ``relightnet avatar`` does (:func:`~relightnet.pipeline.avatar.smooth_video_lights`):
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
:func:`~relightnet.io.image.linear_to_srgb`) with :mod:`relightnet.pipeline.metrics`: RMSE,
PSNR, SSIM per frame, and the temporal error per pair of frames. No exposure matching: the
lights of the data are on an absolute scale. The light error (irradiance L2,
:func:`~relightnet.temporal.light_error`) compares L̂ and L̃ with the truth.

Aggregates: per clip, the mean over its frames (PSNR: mean of the per-frame dB values) and
the temporal error pooled over its frame pairs; over the run, the mean over all frames of
all clips, and the mean of the clips' temporal and light errors. The report's files are
described in :mod:`relightnet.pipeline.compare_report`.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, check_device, sh_order_from_count
from ..io.image import linear_to_srgb, srgb_to_linear, to_uint8
from ..model.network import photo_albedo
from ..sh.io import resize_sh
from ..temporal import jitter, light_distance, light_error
from . import metrics as M
from .avatar import SMOOTHING, smooth_video_lights
from .backends import as_predictor

logger = logging.getLogger(__name__)

__all__ = ["PATHS", "LIGHTS", "CLIP_FIELDS", "ClipOutputs", "CompareResult", "source_light",
           "compare_clip", "clip_metrics", "compare"]

#: The two paths and the three lights each is shaded with (the row order of the tables).
PATHS = ("2d", "3d")
LIGHTS = ("true", "raw", "smoothed")
#: Frame rate of the generated clips (``meta["fps"]``).
CLIP_FPS = 30.0
#: Arrays of a clip that the comparison reads.
CLIP_FIELDS = ("image", "image_composite", "mask", "albedo", "transport", "light", "background")


@dataclass(frozen=True, eq=False)
class ClipOutputs:
    """What :func:`compare_clip` makes for one clip (channels-last, linear RGB).

    Attributes:
        lights: ``"true"``, ``"raw"``, ``"smoothed"`` → (T, K, 3), K of the data.
        renders: ``(path, light)`` → (T, H, W, 3) output of a path under a light, 0 off its mask.
        alpha_3d: (T, H, W) coverage of the 3D path's rasterization.
        source: (T, H, W, 3) the 2D path's input image I_src (linear).
        outliers, switches: (T,) bool, what the smoother flagged (all False without smoothing).
        seconds: time spent per stage (``cnn``, ``prt``, ``render``).
    """

    lights: dict
    renders: dict
    alpha_3d: torch.Tensor
    source: torch.Tensor
    outliers: torch.Tensor
    switches: torch.Tensor
    seconds: dict = field(default_factory=dict)


@dataclass(frozen=True)
class CompareResult:
    """What :func:`compare` returns: the report folder, the files written (name → path), and the
    numbers (the content of ``metrics.json``)."""

    out_dir: Path
    files: dict
    metrics: dict


def source_light(name: str = "studio", lmax: int = 2, level: float = 1.0) -> torch.Tensor:
    """The 2D path's fixed source light: a preset scaled so that its level is ``level``.

    The level is the data generator's exposure rule (:mod:`relightnet.data.lights`: the
    largest luminance of the irradiance over all normals), so I_src is exposed like the data.

    Returns:
        (K, 3) float32, K = (lmax+1)².
    """
    from ..data.lights import light_level
    from ..sh import preset_light

    sh = preset_light(name, lmax)
    return (sh * (level / light_level(sh))).float()


def _shade(albedo: torch.Tensor, transport: torch.Tensor, lights: torch.Tensor) -> torch.Tensor:
    """(T, H, W, 3) albedo ⊙ (transport (T, H, W, K) · lights (T, K, 3))."""
    return albedo * torch.einsum("thwk,tkc->thwc", transport, lights.to(transport))


def compare_clip(model, clip: dict, geometry, n_dirs: int = 64, prt_seed: int | None = 0, smoothing: str = "auto",
                 source: str = "studio", bounces: int = 0, tick=None, cnn_albedo: bool = False) -> ClipOutputs:
    """Run both paths on one clip (module docstring).

    Args:
        model: the CNN: a :class:`~relightnet.model.RelightNet` (eval mode, any device; run at its
            training size) or a predictor of :mod:`relightnet.pipeline.backends` (torch or ONNX).
        clip: the clip's arrays as stored (numpy, leading T): :data:`CLIP_FIELDS`.
        geometry: its :class:`~relightnet.data.render_sample.ClipGeometry` (T frames).
        n_dirs, prt_seed, bounces: the 3D path's PRT (directions, their rotation, interreflections; a
            bounce reflects off 0.5-grey surfaces, ``vertex_transport``'s default).
        smoothing: one of :data:`SMOOTHING`.
        source: preset name of the 2D path's source light.
        tick: optional callable, called after every frame.
        cnn_albedo: the 2D path relights the CNN's albedo, not the photo's (module docstring).

    Returns:
        :class:`ClipOutputs`.
    """
    from ..prt import vertex_transport
    from ..render.frame import render_mesh

    true = torch.from_numpy(np.asarray(clip["light"], np.float32))
    T, K = true.shape[0], true.shape[1]
    lmax = sh_order_from_count(K)
    predict = as_predictor(model)
    mask = torch.from_numpy(np.asarray(clip["mask"], np.float32))
    comp = torch.from_numpy(np.asarray(clip["image_composite"])).permute(0, 3, 1, 2)
    albedo = torch.from_numpy(np.asarray(clip["albedo"], np.float32))
    src = _shade(albedo, torch.from_numpy(np.asarray(clip["transport"], np.float32)),
                 source_light(source, lmax)[None].expand(T, -1, -1))
    if geometry.verts.shape[0] != T:
        raise InputError(f"geometry: {geometry.verts.shape[0]} frames for a clip of {T}")
    secs = {"cnn": 0.0, "prt": 0.0, "render": 0.0}
    raw, evs, priors, a2, t2, a3, t3, al3 = [], [], [], [], [], [], [], []
    for t in range(T):
        c0 = time.perf_counter()
        light, ev, prior = predict.light_evidence(comp[t], mask[t])
        raw.append(resize_sh(light.float().cpu(), lmax))
        evs.append(ev)
        priors.append(prior)
        img = to_uint8(src[t]).permute(2, 0, 1)
        p2 = predict(img, mask[t])
        a = p2.albedo if cnn_albedo else photo_albedo(srgb_to_linear(img.float() / 255)[None].to(p2.albedo), p2)
        a2.append(a[0].permute(1, 2, 0).float().cpu())
        t2.append(p2.transport[0].permute(1, 2, 0).float().cpu())
        c1 = time.perf_counter()
        Tv = vertex_transport(geometry.verts[t], geometry.faces, geometry.normals[t], lmax=lmax,
                              n_dirs=n_dirs, occlusion=True, bounces=bounces, seed=prt_seed,
                              threads=torch.get_num_threads())
        c2 = time.perf_counter()
        rend = render_mesh(geometry.verts[t], geometry.faces, Tv, geometry.albedo, true[t], geometry.camera,
                           maps=True)
        a3.append(rend.albedo[0])
        t3.append(rend.transport[0])
        al3.append(rend.alpha[0])
        c3 = time.perf_counter()
        secs["cnn"] += c1 - c0
        secs["prt"] += c2 - c1
        secs["render"] += c3 - c2
        if tick is not None:
            tick()
    raw = torch.stack(raw)
    smoothed, outliers, switches = smooth_video_lights(raw, smoothing, *_stack_evidence(evs, priors),
                                                       predict.solve_reg, CLIP_FPS)
    smoothed = resize_sh(smoothed, lmax)
    lights = {"true": true, "raw": raw, "smoothed": smoothed}
    a2, t2, a3, t3, al3 = (torch.stack(x) for x in (a2, t2, a3, t3, al3))
    renders = {}
    for name, L in lights.items():
        renders[("2d", name)] = _shade(a2, t2, resize_sh(L, predict.lmax))
        renders[("3d", name)] = _shade(a3, t3, L) * al3[..., None]
    return ClipOutputs(lights, renders, al3, src, outliers, switches, secs)


def _srgb(x: torch.Tensor) -> torch.Tensor:
    """(T, H, W, 3) linear → (T, 3, H, W) sRGB-encoded in [0, 1]."""
    return linear_to_srgb(x.clamp(0, 1)).permute(0, 3, 1, 2)


def _floats(x: torch.Tensor) -> list:
    return [float(v) for v in x.flatten()]


def clip_metrics(out: ClipOutputs, gt: torch.Tensor, mask: torch.Tensor) -> dict:
    """The numbers of one clip.

    Args:
        out: a clip's :class:`ClipOutputs`.
        gt: (T, H, W, 3) the true relit frames (linear).
        mask: (T, H, W) the ground-truth mask.

    Returns:
        ``{"rows": [{"path", "light", "rmse", "psnr", "ssim", "temporal", "per_frame": {...}}, ...] (6),
        "light": {"raw"|"smoothed": {"error", "relative", "jitter", "per_frame"}, "true": {"jitter"}},
        "mask_iou_3d", "smoother_outliers", "smoother_switches"}``; per-frame lists have T entries
        (``temporal``: T − 1, empty for a single frame); jitter is NaN below 3 frames.
    """
    g = _srgb(gt)
    rows = []
    for path in PATHS:
        for light in LIGHTS:
            x = _srgb(out.renders[(path, light)])
            per = {"rmse": M.masked_rmse(x, g, mask), "psnr": M.psnr(x, g, mask), "ssim": M.ssim(x, g, mask)}
            te = M.temporal_error(x, g, mask, reduction="none") if len(g) > 1 else torch.zeros(0)
            row = {"path": path, "light": light, **{k: float(v.mean()) for k, v in per.items()},
                   "temporal": float(M.temporal_error(x, g, mask)) if len(g) > 1 else math.nan,
                   "per_frame": {**{k: _floats(v) for k, v in per.items()}, "temporal": _floats(te)}}
            rows.append(row)
    true = out.lights["true"].double()
    lights = {}
    for name in ("raw", "smoothed"):
        est = out.lights[name].double()
        lights[name] = {"error": float(light_error(est, true)), "relative": float(light_error(est, true, True)),
                        "per_frame": _floats(light_distance(est, true))}
    for name in ("raw", "smoothed", "true"):
        lights.setdefault(name, {})["jitter"] = float(jitter(out.lights[name].double())) if len(g) >= 3 else math.nan
    gm, am = mask > 0.5, out.alpha_3d > 0.5
    return {"rows": rows, "light": lights, "mask_iou_3d": float((gm & am).sum() / (gm | am).sum().clamp_min(1)),
            "smoother_outliers": torch.nonzero(out.outliers).flatten().tolist(),
            "smoother_switches": torch.nonzero(out.switches).flatten().tolist()}


# ----------------------------------------------------------------------------- the job


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

    n = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        return clip_geometry(cfg, split, index, T, assets)
    finally:
        torch.set_num_threads(n)


def _stack_evidence(evs: list, priors: list):
    """Per-frame (Evidence | None, prior | None) lists → (Evidence (T, ...) | None, priors (T, K, 3) | None)."""
    from ..model.light_solve import Evidence

    if any(e is None for e in evs):
        return None, None
    ev = Evidence(torch.cat([e[0] for e in evs]).float().cpu(), torch.cat([e[1] for e in evs]).float().cpu())
    return ev, (None if any(p is None for p in priors) else torch.stack(priors).float().cpu())


@torch.no_grad()
def compare(data_dir, out_dir, checkpoint=None, split: str = "test", clips: int | None = None, n_dirs: int = 64,
            smoothing: str = "auto", device: str = "cpu", progress: bool = True, prt_seed: int = 0,
            source: str = "studio", size: int | None = None, bounces: int = 0, backend: str = "torch",
            body=None, cnn_albedo: bool = False) -> CompareResult:
    """Compare the 2D and 3D paths on the clips of a sequence dataset and write a report (module docstring).

    Args:
        data_dir: a dataset folder made by ``relightnet synth`` with ``sequence_frames > 0``.
        out_dir: the report folder (made if needed; the files of an earlier report are replaced).
            Everything is made in a hidden folder beside it and moved in at the end, so a failed
            run leaves nothing.
        checkpoint: the CNN's checkpoint (default: the shipped model); with ``backend="onnx"`` also an
            ``.onnx`` file (a checkpoint is exported once, :func:`~relightnet.pipeline.backends.make_predictor`).
        split: which split's clips.
        clips: the first N clips (default: all).
        n_dirs, prt_seed, bounces: the 3D path's PRT directions, their rotation seed, interreflections.
        smoothing: one of :data:`SMOOTHING` (default ``auto``: ``pooled`` for a network that solves its
            light, else ``hermite``).
        device: for the CNN (``"cpu"``, ``"cuda"``); PRT and rasterization run on the CPU.
        progress: show a tqdm bar (frames/s).
        source: preset name of the 2D path's source light.
        size: the CNN's working size, a multiple of 16 (default: its training size).
        backend: where the CNN runs, ``"torch"`` or ``"onnx"`` (CPU).
        body: an :class:`~relightnet.body.AnnyBody` or ``SynthAssets`` to reuse (default: a new one).
        cnn_albedo: the 2D path relights the CNN's albedo (default: the photo's, as relight-video).

    Returns:
        :class:`CompareResult`.

    Raises:
        InputError: a missing or unusable dataset, an empty split, a bad checkpoint or option.
    """
    from tqdm import tqdm

    from ..data.sample import assets_for
    from ..io import VideoWriter
    from ..model.checkpoint import shipped_checkpoint
    from ..sh import preset_names
    from . import compare_report as R
    from .backends import make_predictor

    t_start = time.perf_counter()
    if smoothing not in SMOOTHING:
        raise InputError(f"smoothing: expected one of {', '.join(SMOOTHING)}, got {smoothing!r}")
    for name, v, lo in (("n_dirs", n_dirs, 1), ("clips", clips, 1), ("bounces", bounces, 0)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < lo):
            raise InputError(f"{name}: expected an integer >= {lo}, got {v!r}")
    if source not in preset_names():
        raise InputError(f"source: expected a preset name ({', '.join(preset_names())}), got {source!r}")
    dev = check_device(device, "device")
    cfg, files = _open_data(data_dir, split)
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"{out_dir}: exists and is not a folder")
    if size is not None and (isinstance(size, bool) or not isinstance(size, int) or size < 16 or size % 16):
        raise InputError(f"size: expected a positive multiple of 16, got {size!r}")
    predictor = make_predictor(backend, checkpoint, str(dev))
    if size is not None:
        predictor.size = size
    size = predictor.size if predictor.size is not None else int(getattr(predictor.model, "input_size", 256))
    assets = assets_for(body)
    T = cfg.sequence_frames
    n_total = sum(c for _, c in files) if clips is None else min(clips, sum(c for _, c in files))

    stage = R.staging_dir(out_dir)
    try:
        (stage / "plots").mkdir()
        records, light_arrays = [], {}
        secs = {"cnn": 0.0, "prt": 0.0, "render": 0.0}
        with (tqdm(total=n_total * T, unit="frame", desc="compare", disable=not progress, dynamic_ncols=True) as bar,
              VideoWriter(stage / "side_by_side.mp4", fps=CLIP_FPS) as video):
            for meta, clip in _clips(files, clips):
                index = int(meta["seed"]["index"])
                geo = _one_thread_geometry(cfg, split, index, T, assets)
                out = compare_clip(predictor, clip, geo, n_dirs, prt_seed, smoothing, source, bounces,
                                   tick=lambda: bar.update(1), cnn_albedo=cnn_albedo)
                for k in secs:
                    secs[k] += out.seconds[k]
                mask = torch.from_numpy(np.asarray(clip["mask"], np.float32))
                rec = {"index": index, **clip_metrics(out, torch.from_numpy(np.asarray(clip["image"])), mask),
                       "switch_frames": list(meta.get("switch_frames", [])),
                       "light_source": str(meta.get("light", {}).get("source", "?")),
                       "bounce": bool(meta.get("flags", {}).get("bounce", False))}
                if rec["mask_iou_3d"] < 0.99:
                    logger.warning("clip %d: the 3D path's mask differs from the clip's (IoU %.3f): was the data made "
                                   "by another generator or body-model version?", index, rec["mask_iou_3d"])
                records.append(rec)
                R.add_clip(stage, video, clip, out, rec, light_arrays)
        R.plot_summary(stage / "plots" / "errors.png", stage / "plots" / "light_error.png", records)
        total = time.perf_counter() - t_start
        frames = len(records) * T
        ckpt = str(shipped_checkpoint() if checkpoint is None else Path(checkpoint))
        metrics = {
            "format": "relightnet-compare/1",
            "settings": {"data": str(Path(data_dir)), "split": split, "clips": [r["index"] for r in records],
                         "checkpoint": ckpt, "backend": backend, "size": size, "device": str(dev),
                         "smoothing": smoothing, "smoothing_options": {"outlier_eps": "3mad", "switches": "auto"},
                         "n_dirs": n_dirs,
                         "prt_seed": prt_seed, "bounces": bounces, "source_light": source, "source_level": 1.0,
                         "albedo_2d": "cnn" if cnn_albedo else "photo",
                         "dataset": cfg.to_dict()},
            "timing": {"frames": frames, "total_s": total, "frames_per_s": frames / total,
                       **{f"{k}_s": v for k, v in secs.items()}},
            "summary": R.summarize(records),
            "clips": records,
        }
        R.write_json(stage / "metrics.json", metrics)
        R.write_lights(stage / "lights.npz", light_arrays)
        with (stage / "report.md").open("w", encoding="utf-8") as f:
            f.write(R.format_report(metrics))
        files_out = R.publish(stage, out_dir)
    except BaseException:
        import shutil

        shutil.rmtree(stage, ignore_errors=True)
        raise
    logger.info("wrote %s (%d clips, %d frames, %.1f s)", out_dir, len(records), frames, total)
    return CompareResult(out_dir, files_out, metrics)
