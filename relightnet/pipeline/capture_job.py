"""``relightnet capture``: a filmed person made an avatar file (:mod:`relightnet.capture`).

1. **Fit** the largest person (:func:`relightnet.fit.fit_file`): pose, shape and camera of every
   frame, and the person masks the fit saw.
2. **Light**: the CNN's light of every frame from the person (with those masks), smoothed over
   time as ``avatar`` smooths a target's (:func:`relightnet.temporal.smooth_video_lights`).
3. **Geometry**: per-vertex offsets from the silhouettes (:func:`relightnet.capture.offsets.solve_offsets`);
   a single photo keeps the bare body (one view says nothing about depth).
4. **Texture**: every frame's visible texels de-lit by the shading of that geometry under the
   frame's light and fused (:func:`relightnet.capture.fuse.capture_person`); the unseen filled.
5. The file (:func:`relightnet.capture.save_avatar`), and on request a preview sheet.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import torch

from ..capture.avatar_file import CapturedAvatar, save_avatar
from ..capture.texture import TextureOptions
from ..checks import InputError
from ..fit.job import FitOptions

logger = logging.getLogger(__name__)

__all__ = ["CaptureOptions", "CaptureReport", "capture_file", "frame_masks", "source_lights"]


@dataclass(frozen=True)
class CaptureOptions:
    """How to capture: the texture's options, the fit's, whether to solve offsets (None: for a video, not
    for a photo) and the light smoothing (a name of :data:`relightnet.names.VIDEO_SMOOTHING`)."""

    texture: TextureOptions = field(default_factory=TextureOptions)
    fit: FitOptions = field(default_factory=FitOptions)
    offsets: bool | None = None
    smoothing: str = "auto"


@dataclass(frozen=True, eq=False)
class CaptureReport:
    """What :func:`capture_file` did: ``out``, the ``avatar``, the smoothed ``lights`` (T, K, 3), the silhouette
    IoU of the bare and the offset body against the masks (None without offsets), the capture's
    ``ms_per_frame`` after the fit, the ``fit`` (:class:`~relightnet.fit.FitOutput`), ``seen`` (S, S) bool and,
    when asked, ``raw_texture`` (S, S, 3): the frames fused without de-lighting (for evaluation)."""

    out: Path
    avatar: CapturedAvatar
    lights: torch.Tensor
    iou_body: float | None
    iou_offset: float | None
    ms_per_frame: float
    fit: object = None
    seen: torch.Tensor | None = None
    raw_texture: torch.Tensor | None = None


def frame_masks(masks, n: int):
    """The (H, W) bool mask of each of ``n`` frames from :class:`~relightnet.fit.masks.PackedMasks` (enlarged to the
    frame's size one at a time; None where the person was not found)."""
    for t in range(n):
        m = masks[t:t + 1].unpack()[0]
        yield m if bool(m.any()) else None


def source_lights(predictor, frames, masks, smoothing: str, fps: float) -> torch.Tensor:
    """(T, K, 3) the smoothed light of every frame, estimated from the person (a frame without one takes its
    neighbours' through the smoothing; the first frames' before any person, the first estimate)."""
    from ..sh.light_solve import stack_evidence
    from ..temporal import frame_colour, smooth_video_lights

    raw, evs, priors, have, colours = [], [], [], [], []
    for img, mask in zip(frames, masks, strict=False):
        colours.append(frame_colour(img))
        if mask is None:
            raw.append(None)
            continue
        light, ev, prior = predictor.light_evidence(img, mask)
        raw.append(light.float().cpu())
        evs.append(ev)
        priors.append(prior)
        have.append(len(raw) - 1)
    if not have:
        raise InputError("capture: no frame shows a person")
    filled = [raw[min(have, key=lambda h: abs(h - t))] if x is None else x for t, x in enumerate(raw)]
    raw_t = torch.stack(filled)
    if len(have) != len(raw) or raw_t.shape[0] < 2:
        return smooth_video_lights(raw_t, "hermite" if raw_t.shape[0] >= 2 else "none", fps=fps).smoothed
    ev, prior = stack_evidence(evs, priors)
    return smooth_video_lights(raw_t, smoothing, ev, prior, predictor.solve_reg, fps,
                               colour=torch.stack(colours)).smoothed


def capture_file(source, out, predictor, options: CaptureOptions = CaptureOptions(), preview=None,
                 models=None, raw: bool = False, fb=None) -> CaptureReport:
    """Capture the largest person of a video or a photo into an avatar file (module docstring).

    Args:
        source: a video or a photo of a person. out: the avatar file (``.avatar.npz``), written atomically.
        predictor: the CNN's predictor (:func:`relightnet.pipeline.backends.make_predictor`), for the light.
        options: :class:`CaptureOptions`. preview: a ``.png`` sheet to draw (:func:`.capture_preview.preview_sheet`).
        models: the segmentation's :class:`~relightnet.segment.PersonModels` (made when None).
        raw: also fuse the raw colours (:attr:`CaptureReport.raw_texture`).
        fb: the :class:`~relightnet.fit.FitBody` to fit with (made when None).

    Raises:
        InputError: no person in the source; ``options.offsets`` asked of a single frame. One line.
    """
    from ..capture.fuse import capture_person
    from ..fit import FitBody
    from ..fit.job import fit_file, media_frames

    fb = FitBody() if fb is None else fb
    fit = fit_file(source, options.fit, fb, models)
    T = fit.result.pose.shape[0]
    if options.offsets and T < 2:
        raise InputError(f"{source}: offsets need at least 2 frames (a video); a photo is captured on the bare body")
    lights = source_lights(predictor, media_frames(source)[0], frame_masks(fit.masks, T), options.smoothing, fit.fps)
    offsets = iou_body = iou_offset = None
    if options.offsets or (options.offsets is None and T >= 2):
        from ..capture.offsets import solve_offsets

        solved = solve_offsets(fit.result, fb, fit.masks)
        offsets, iou_body, iou_offset = solved.offsets, solved.iou_body, solved.iou_offset
        logger.info("%s: offsets solved, silhouette IoU %.3f bare -> %.3f with offsets", source, iou_body, iou_offset)
    elif T < 2:
        logger.info("%s: a single photo: only the side facing the camera is seen; the rest is filled", source)
    res = capture_person(fit.result, fb, media_frames(source)[0], frame_masks(fit.masks, T), lights, offsets,
                         options.texture, raw=raw)
    path = save_avatar(out, res.avatar)
    logger.info("%s: wrote %s (%.1f%% of the surface seen, %d frame(s), %.0f ms a frame)", source, path,
                100 * res.avatar.seen_share, res.avatar.frames, res.ms_per_frame)
    if preview is not None:
        from .capture_preview import preview_sheet

        preview_sheet(preview, res.avatar, fb.body)
    return CaptureReport(path, res.avatar, lights, iou_body, iou_offset, res.ms_per_frame, fit, res.seen,
                         res.raw_texture)
