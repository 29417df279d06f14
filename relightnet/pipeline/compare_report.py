"""The files of ``relightnet compare`` (:mod:`relightnet.pipeline.compare`): report, numbers, plots, video.

A report folder holds:

- ``report.md``: the settings, the table of the six (path, light) rows (RMSE, PSNR, SSIM,
  temporal error: means over all frames), the light-error table, a row per clip;
- ``metrics.json``: every number, per frame too. Strict JSON: non-finite numbers (the PSNR of
  identical images is +∞) are written as the strings ``"inf"``, ``"-inf"``, ``"nan"``
  (``float(s)`` reads them back);
- ``lights.npz``: per clip ``clip{index}_true``, ``_raw``, ``_smoothed`` (T, K, 3) and
  ``_outliers``, ``_switches`` (T,) bool;
- ``plots/errors.png`` (RMSE and SSIM per frame, mean over the clips, for the six outputs),
  ``plots/light_error.png`` (light error per frame, raw vs smoothed), and per clip
  ``plots/clip{index:05d}_errors.png`` and ``plots/clip{index:05d}_light.png`` (the luminance
  of SH coefficients 0–3 per frame: raw, smoothed, true, with the smoother's outliers and switches,
  :func:`relightnet.temporal.plot.light_curves_png`);
- ``side_by_side.mp4``: every clip one after the other, each frame four panels —
  target frame (input of the light estimate) | 2D path | 3D path (both under the smoothed
  light) | ground truth, the renders composited over the clip's background.
"""

from __future__ import annotations

import io
import json
import math
import os
import shutil
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError
from ..color import linear_to_srgb
from ..io import atomic_write
from ..io.atomic import remove_stale, temp_path

__all__ = ["staging_dir", "publish", "summarize", "json_safe", "write_json", "write_lights", "side_by_side", "add_clip",
           "to_uint8_seq", "plot_clip", "plot_summary", "format_report"]

_COLORS = {"true": "tab:green", "raw": "tab:red", "smoothed": "tab:blue"}
_STYLES = {"2d": "-", "3d": "--"}


def json_safe(x):
    """Nested dicts/lists with non-finite floats replaced by ``"inf"``, ``"-inf"``, ``"nan"``."""
    if isinstance(x, dict):
        return {str(k): json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [json_safe(v) for v in x]
    if isinstance(x, float | np.floating) and not math.isfinite(x):
        return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
    if isinstance(x, np.integer | np.bool_):
        return x.item()
    return x


def write_json(path, data: dict) -> None:
    """Strict JSON (see :func:`json_safe`), atomically."""
    with atomic_write(path, "w") as f:
        f.write(json.dumps(json_safe(data), indent=1, allow_nan=False) + "\n")


def write_lights(path, lights: dict) -> None:
    """An ``.npz`` of named arrays, atomically."""
    with atomic_write(path) as f:
        np.savez_compressed(f, **{k: np.asarray(v) for k, v in lights.items()})


def staging_dir(out_dir: Path) -> Path:
    """A fresh hidden folder next to ``out_dir`` (same file system) where the report is made."""
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"{out_dir}: exists and is not a folder")
    anchor = out_dir.absolute().parent
    while not anchor.exists():
        anchor = anchor.parent
    if not anchor.is_dir():
        raise InputError(f"{out_dir}: {anchor} is not a folder")
    target = anchor / out_dir.name
    remove_stale(target)  # staging folders of killed runs
    stage = temp_path(target, "stage")
    stage.mkdir()
    return stage


def publish(stage: Path, out_dir: Path) -> dict:
    """Move every file of ``stage`` into ``out_dir`` (one ``os.replace`` each); drop stale clip plots."""
    out_dir.mkdir(parents=True, exist_ok=True)
    files = {}
    for p in sorted(stage.rglob("*")):
        if p.is_file():
            rel = p.relative_to(stage)
            dst = out_dir / rel
            dst.parent.mkdir(parents=True, exist_ok=True)
            os.replace(p, dst)
            files[rel.as_posix()] = dst
    for old in (out_dir / "plots").glob("clip*.png"):
        if f"plots/{old.name}" not in files:
            old.unlink()
    shutil.rmtree(stage, ignore_errors=True)
    return files


def summarize(records: list) -> dict:
    """The run's means from the clips' records: per (path, light) row over all frames, light errors over clips."""
    rows = []
    for i, r0 in enumerate(records[0]["rows"]):
        cat = {k: np.concatenate([np.asarray(c["rows"][i]["per_frame"][k], float) for c in records])
               for k in ("rmse", "psnr", "ssim")}
        temporal = [c["rows"][i]["temporal"] for c in records if math.isfinite(c["rows"][i]["temporal"])]
        rows.append({"path": r0["path"], "light": r0["light"], **{k: float(v.mean()) for k, v in cat.items()},
                     "temporal": float(np.mean(temporal)) if temporal else math.nan})
    light = {n: {k: float(np.mean([c["light"][n][k] for c in records])) for k in ("error", "relative", "jitter")}
             for n in ("raw", "smoothed")}
    light["true"] = {"jitter": float(np.mean([c["light"]["true"]["jitter"] for c in records]))}
    return {"rows": rows, "light": light}


def side_by_side(clip: dict, out) -> np.ndarray:
    """The video frames of one clip: input | 2D | 3D | ground truth.

    Args:
        clip: the clip's arrays (``image_composite``, ``image``, ``mask``, ``background``; leading T).
        out: its :class:`~relightnet.pipeline.compare.ClipOutputs`.

    Returns:
        (T, H, 4W, 3) uint8 sRGB.
    """
    m = torch.from_numpy(np.asarray(clip["mask"], np.float32))[..., None]
    bg = torch.from_numpy(np.asarray(clip["background"], np.float32))
    a3 = out.alpha_3d[..., None]
    panels = [
        torch.from_numpy(np.asarray(clip["image_composite"])),
        to_uint8_seq(out.renders[("2d", "smoothed")] * m + bg * (1 - m)),
        to_uint8_seq(out.renders[("3d", "smoothed")] + bg * (1 - a3)),
        to_uint8_seq(torch.from_numpy(np.asarray(clip["image"], np.float32)) * m + bg * (1 - m)),
    ]
    return torch.cat(panels, dim=2).numpy()


def add_clip(stage, video, clip: dict, out, record: dict, light_arrays: dict) -> None:
    """One clip's share of the report: its video frames, its lights (into ``light_arrays``), its two plots."""
    index = record["index"]
    for name, L in out.lights.items():
        light_arrays[f"clip{index}_{name}"] = L.numpy()
    light_arrays[f"clip{index}_outliers"] = out.outliers.numpy()
    light_arrays[f"clip{index}_switches"] = out.switches.numpy()
    for frame in side_by_side(clip, out):
        video.write(frame)
    plots = Path(stage) / "plots"
    plot_clip(plots / f"clip{index:05d}_errors.png", plots / f"clip{index:05d}_light.png", record, out.lights,
              out.outliers, out.switches)


def to_uint8_seq(x: torch.Tensor) -> torch.Tensor:
    """(T, H, W, 3) linear → uint8 sRGB (what :func:`~relightnet.io.to_uint8` does to each frame)."""
    return (linear_to_srgb(x.clamp(0, 1)) * 255).round().to(torch.uint8)


def _figure(rows: int, cols: int, w: float = 4.2, h: float = 2.8):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(w * cols, h * rows), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.subplots(rows, cols, squeeze=False).ravel()


def _save(fig, path) -> None:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    with atomic_write(path) as f:
        f.write(buf.getvalue())


def _frames_axis(ax) -> None:
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("frame")
    ax.grid(alpha=0.3)


def _vlines(ax, frames) -> None:
    for s in frames:
        ax.axvline(s - 0.5, color="0.5", lw=0.8, ls=":")


def _error_panels(axes, rows: list, key_label) -> None:
    for ax, (key, label) in zip(axes, key_label, strict=True):
        for r in rows:
            y = np.asarray(r["per_frame"][key], float)
            ax.plot(np.arange(len(y)), y, _STYLES[r["path"]], color=_COLORS[r["light"]], lw=1.3,
                    label=f"{r['path'].upper()}, {r['light']} light")
        _frames_axis(ax)
        ax.set_ylabel(label)
    axes[0].legend(fontsize=7, ncol=2)


def plot_clip(errors_path, light_path, record: dict, lights: dict, outliers, switches) -> None:
    """Per-clip plots: error curves of the six outputs, and light curves.

    Args:
        record: the clip's entry of ``metrics.json`` (``rows``, ``index``, ``switch_frames``).
        lights: ``"true"``, ``"raw"``, ``"smoothed"`` → (T, K, 3).
        outliers, switches: (T,) bool flags of the smoother.
    """
    fig, axes = _figure(1, 2)
    _error_panels(axes, record["rows"], [("rmse", "RMSE (sRGB)"), ("ssim", "SSIM")])
    for ax in axes:
        _vlines(ax, record["switch_frames"])
    fig.suptitle(f"clip {record['index']}: error per frame (solid 2D, dashed 3D; dotted: light switch)")
    _save(fig, errors_path)

    from ..temporal.plot import light_curves_png

    png = light_curves_png(lights["raw"], lights["smoothed"], lights["true"], torch.as_tensor(outliers),
                           torch.as_tensor(switches), title=f"clip {record['index']}: light (luminance of SH "
                           f"coefficients), true switches at {record['switch_frames'] or 'none'}")
    with atomic_write(light_path) as f:
        f.write(png)


def plot_summary(errors_path, light_path, records: list) -> None:
    """Mean per-frame curves over the clips (clips of one dataset share T)."""
    rows = []
    for i, r0 in enumerate(records[0]["rows"]):
        per = {key: np.mean([np.asarray(c["rows"][i]["per_frame"][key], float) for c in records], axis=0)
               for key in ("rmse", "ssim")}
        rows.append({"path": r0["path"], "light": r0["light"], "per_frame": per})
    fig, axes = _figure(1, 2)
    _error_panels(axes, rows, [("rmse", "RMSE (sRGB), mean over clips"), ("ssim", "SSIM, mean over clips")])
    fig.suptitle(f"{len(records)} clip(s): error per frame (solid 2D, dashed 3D)")
    _save(fig, errors_path)

    fig, axes = _figure(1, 1, w=5.5, h=3.2)
    for name in ("raw", "smoothed"):
        y = np.mean([np.asarray(c["light"][name]["per_frame"], float) for c in records], axis=0)
        axes[0].plot(np.arange(len(y)), y, color=_COLORS[name], lw=1.5, label=f"{name} estimate")
    _frames_axis(axes[0])
    axes[0].set_ylabel("light error (irradiance L2)")
    axes[0].set_title(f"light error per frame, mean over {len(records)} clip(s)", fontsize=10)
    axes[0].legend(fontsize=8)
    _save(fig, light_path)


def _f(x, digits: int = 4) -> str:
    if isinstance(x, str):
        x = float(x)
    if math.isnan(x):
        return "—"
    if math.isinf(x):
        return "∞" if x > 0 else "−∞"
    return f"{x:.{digits}f}"


def format_report(m: dict) -> str:
    """``report.md`` from the content of ``metrics.json``."""
    s, d = m["settings"], m["settings"]["dataset"]
    tm = m["timing"]
    clips = m["clips"]
    smooth = ("none (L̃ = L̂)" if s["smoothing"] == "none"
              else f"{s['smoothing']} (outliers: 3 MAD; switches: auto)")
    lines = [
        "# relightnet compare: 2D baseline vs 3D path",
        "",
        f"- Data: `{s['data']}`, split `{s['split']}`: {len(clips)} clip(s) × {d['sequence_frames']} frames at "
        f"{d['res']}², K = {(d['lmax'] + 1) ** 2} (ground-truth PRT: {d['n_dirs']} directions); clips "
        f"{', '.join(str(c['index']) for c in clips)}.",
        f"- Checkpoint: `{s['checkpoint']}` (CNN working size {s['size']}, device {s['device']}).",
        f"- Light: CNN estimate per target frame; smoothing {smooth}.",
        f"- 2D path: CNN transport from the subject under the `{s['source_light']}` preset (level 1), "
        + ("the CNN's albedo" if s.get("albedo_2d") == "cnn" else "the photo's albedo (photo / predicted shading)")
        + ", shaded with each light.",
        f"- 3D path: the clip's mesh, PRT with occlusion, {s['n_dirs']} directions (seed {s['prt_seed']}), "
        f"{s['bounces']} bounce(s); the true albedo texture.",
        f"- Run: {tm['frames']} frames in {tm['total_s']:.1f} s ({tm['frames_per_s']:.2f} frames/s): CNN "
        f"{tm['cnn_s']:.1f} s, PRT {tm['prt_s']:.1f} s, rasterization {tm['render_s']:.1f} s.",
        "",
        "Ground truth: the clip's relit person (albedo ⊙ (transport · L_t)). Metrics on sRGB values in [0, 1], "
        "inside the ground-truth mask; means over all frames of all clips (PSNR: mean of per-frame dB); "
        "temporal error = mean |(out_t − out_t−1) − (gt_t − gt_t−1)| on pixels masked in both frames, mean "
        "over clips.",
        "",
        "## Relit frames vs ground truth",
        "",
        "| path | light | RMSE ↓ | PSNR (dB) ↑ | SSIM ↑ | temporal error ↓ |",
        "|---|---|---|---|---|---|",
    ]
    names = {"true": "true L_t", "raw": "estimated L̂_t", "smoothed": "smoothed L̃_t"}
    for r in m["summary"]["rows"]:
        lines.append(f"| {r['path'].upper()} | {names[r['light']]} | {_f(r['rmse'])} | {_f(r['psnr'], 2)} | "
                     f"{_f(r['ssim'])} | {_f(r['temporal'])} |")
    li = m["summary"]["light"]
    lines += ["", "## Light estimate (irradiance L2 distance to the true light; mean over clips)", "",
              "| light | error ↓ | relative error ↓ | jitter |", "|---|---|---|---|"]
    for name in ("raw", "smoothed"):
        lines.append(f"| {names[name]} | {_f(li[name]['error'])} | {_f(li[name]['relative'])} | "
                     f"{_f(li[name]['jitter'])} |")
    lines.append(f"| true L_t | 0 | 0 | {_f(li['true']['jitter'])} |")
    lines += ["", "Jitter: mean irradiance-L2 norm of the second difference over time (needs ≥ 3 frames); the true "
              "light's includes its switches.", "",
              "## Per clip", "",
              "| clip | light | switch at | 2D RMSE (L̃) | 3D RMSE (L̃) | 3D RMSE (L) | light error L̂ | light error L̃ "
              "| 3D mask IoU |", "|---|---|---|---|---|---|---|---|---|"]
    for c in clips:
        r = {(x["path"], x["light"]): x for x in c["rows"]}
        lines.append(f"| {c['index']} | {c['light_source']} | {', '.join(map(str, c['switch_frames'])) or '—'} | "
                     f"{_f(r[('2d', 'smoothed')]['rmse'])} | {_f(r[('3d', 'smoothed')]['rmse'])} | "
                     f"{_f(r[('3d', 'true')]['rmse'])} | {_f(c['light']['raw']['error'])} | "
                     f"{_f(c['light']['smoothed']['error'])} | {_f(c['mask_iou_3d'])} |")
    lines += ["", "## Files", "",
              "- `metrics.json`: every number, per frame too (non-finite values as the strings \"inf\", \"nan\").",
              "- `lights.npz`: true, raw and smoothed lights per clip, and the smoother's outlier and switch flags.",
              "- `plots/errors.png`, `plots/light_error.png`: mean per-frame curves; `plots/clip*_errors.png`, "
              "`plots/clip*_light.png`: per clip.",
              "- `side_by_side.mp4`: target frame | 2D (L̃) | 3D (L̃) | ground truth; clips in the order above, "
              f"{d['sequence_frames']} frames each.", ""]
    return "\n".join(lines)
