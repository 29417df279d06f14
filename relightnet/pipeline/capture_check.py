"""The capture checked against its own source: the captured avatar re-rendered where the person was.

:func:`reproject` renders the captured person (offsets and texture) in the source's camera, in every
frame's fitted pose, under that frame's estimated light, and composites it over the source frame
(``--reproject``): a person compares it with the source, and the PSNR inside the person's mask
measures it. With ``mask_out`` it also writes the captured mesh's silhouette in the source camera
(``--mask-out``, as ``fit --mask-out`` writes the bare body's), and reports its IoU with the masks.
"""

from __future__ import annotations

import math
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np
import torch

__all__ = ["Reprojection", "reproject"]


@dataclass(frozen=True)
class Reprojection:
    """``psnr``: dB inside the person's masks over the frames with a person (sRGB, 8-bit scale); ``iou``:
    mean silhouette IoU of the captured mesh with those masks; ``frames``: frames compared."""

    psnr: float
    iou: float
    frames: int


def reproject(report, source, fb, out: Path | None = None, mask_out: Path | None = None) -> Reprojection:
    """Re-render a capture over its source (module docstring).

    Args:
        report: the :class:`~relightnet.pipeline.capture_job.CaptureReport` of ``source``.
        source: the captured video or photo. fb: the :class:`~relightnet.fit.FitBody` of the capture.
        out: the composited video (.mp4/.mkv; a .png for a photo), or None. mask_out: the silhouettes
            (a mask video .mkv/.mp4, a .png for a photo), or None.
    """
    from ..capture import CapturedBody
    from ..color import linear_to_srgb
    from ..fit.job import media_frames
    from ..fit.preview import fit_camera
    from ..prt import PrtSettings
    from ..render.jobs import render_body_frames
    from .capture_job import frame_masks

    result = report.fit.result
    T = result.pose.shape[0]
    frames, fps, photo = media_frames(source)
    cb = CapturedBody(fb.body, report.avatar)
    camera = fit_camera(result)
    params = {"pose": fb.full_pose(result.pose), "trans": result.trans}
    renders = render_body_frames(cb, params, report.lights, cb.albedo, camera=camera, n_frames=T,
                                 prt=PrtSettings(n_dirs=64), visible_only=True, box=True)
    sq, n_px, ious, used = 0.0, 0, [], 0
    with _writers(out, mask_out, fps, photo) as write:
        for fr, img, mask in zip(renders, frames, frame_masks(report.fit.masks, T), strict=False):
            src = (img.permute(1, 2, 0).clamp(0, 1) * 255).round().to(torch.uint8)
            r = fr.render
            pix = r.frags.region.to_frame(r.frags.pix)
            fg = (linear_to_srgb(r.pix_image.clamp(0, 1)).clamp(0, 1) * 255).round().to(torch.uint8)
            comp = src.clone()
            comp.view(-1, 3).index_copy_(0, pix, fg)
            cover = torch.zeros(src.shape[0] * src.shape[1], dtype=torch.bool)
            cover[pix] = True
            cover = cover.view(src.shape[:2])
            write(comp.numpy(), cover)
            if mask is None:
                continue
            d = comp[mask].float() - src[mask].float()
            sq, n_px, used = sq + float(d.square().sum()), n_px + d.numel(), used + 1
            ious.append(float((cover & mask).sum()) / max(float((cover | mask).sum()), 1.0))
    mse = sq / max(n_px, 1)
    psnr = 10 * math.log10(255.0 ** 2 / mse) if mse > 0 else float("inf")
    return Reprojection(psnr, float(np.mean(ious)) if ious else float("nan"), used)


@contextmanager
def _writers(out, mask_out, fps: float, photo: bool):
    """``write(frame (H, W, 3) uint8, cover (H, W) bool)`` to the outputs asked (a video each, or a PNG each for
    a photo); the videos are closed (and so written atomically) on leaving."""
    from ..io import VideoWriter

    with ExitStack() as stack:
        sinks = []
        for path in (out, mask_out):
            if path is None:
                sinks.append(None)
            elif photo:
                sinks.append(partial(_write_png, Path(path)))
            else:
                sinks.append(stack.enter_context(VideoWriter(path, fps=fps, gray=path is mask_out)).write)

        def write(frame: np.ndarray, cover: torch.Tensor) -> None:
            if sinks[0] is not None:
                sinks[0](frame)
            if sinks[1] is not None:
                sinks[1](np.repeat(cover.numpy().astype(np.uint8)[..., None] * 255, 3, axis=2))

        yield write


def _write_png(path: Path, frame: np.ndarray) -> None:
    from ..io import write_image

    write_image(path, frame, srgb=False)
