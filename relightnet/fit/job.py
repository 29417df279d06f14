"""The whole fit of a photo or a video file: read, observe, fit, smooth, place, write.

:func:`fit_file` is what ``relightnet fit`` and ``avatar --motion-from`` call; the outputs
(:func:`write_preview`, :func:`write_fit_masks`) re-read the input, so no video is held in memory.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import torch

from ..checks import InputError
from ..io.probe import PHOTO_SUFFIXES
from .body_model import FitBody
from .camera import DEFAULT_FOV_DEG, default_intrinsics, exif_intrinsics
from .observe import observe_frames
from .smooth import place_in_world, smooth_motion
from .solve import MAX_FIT_FRAMES, FitResult, FitWeights, fit_observations

logger = logging.getLogger(__name__)

__all__ = ["FitOptions", "FitOutput", "media_frames", "fit_file", "motion_for_avatar",
           "write_preview", "write_fit_masks"]

#: Frames of the whole posed mesh made together (a video's foot skating is measured on its landmarks).
_BODY_CHUNK = 16

#: Inputs read as a photo; anything else is read as a video.


@dataclass(frozen=True)
class FitOptions:
    """How to fit: iterations (first window, later windows), window length, shape on/off,
    the final smoothing (Gaussian sigma in frames, 0: none), the field of view used when the
    input has no EXIF focal length, and the term weights."""

    iters: int = 120
    warm_iters: int = 50
    window: int = 8
    fit_shape: bool = True
    smooth_sigma: float = 1.5
    fov_deg: float = DEFAULT_FOV_DEG
    weights: FitWeights = FitWeights()


@dataclass(frozen=True, eq=False)
class FitOutput:
    """raw: the fit before smoothing; result: after; motion: the world-frame AnnyMotion; fps; masks: the
    person masks the fit saw (:class:`~relightnet.fit.masks.PackedMasks`, each window at its working resolution)."""

    raw: FitResult
    result: FitResult
    motion: object
    fps: float
    masks: object = None


def media_frames(path: str | Path) -> tuple[Iterator[torch.Tensor], float, bool]:
    """(3, H, W) sRGB frames in [0, 1] of a photo or a video, its frame rate, and whether it is a photo."""
    from ..io import read_image, read_video, video_info

    path = Path(path)
    if path.suffix.lower() in PHOTO_SUFFIXES:
        return iter([read_image(path).permute(2, 0, 1).contiguous()]), 30.0, True
    info = video_info(path)
    frames = (torch.from_numpy(f).permute(2, 0, 1).float().div_(255) for f in read_video(path))  # one float copy
    return frames, float(info.fps), False


def fit_file(path: str | Path, options: FitOptions = FitOptions(), fb: FitBody | None = None,
             models=None) -> FitOutput:
    """Fit Anny to the largest person of a photo or video.

    Raises:
        InputError: no person in the photo / in any frame of the video; a video of more than
            :data:`~relightnet.fit.job.MAX_FIT_FRAMES` frames (counted from its packets, before any work).
            One line naming the file.
    """
    from ..io import count_frames

    path = Path(path)
    if path.suffix.lower() not in PHOTO_SUFFIXES and (n := count_frames(path)) > MAX_FIT_FRAMES:
        raise InputError(f"{path}: {n} frames; at most {MAX_FIT_FRAMES} frames are fitted (cut the video into parts)")
    frames, fps, photo = media_frames(path)
    obs = observe_frames(frames, models, name=str(path), window=options.window)
    if photo and not bool(obs.found[0]):
        raise InputError(f"{path}: no person found (expected a photo showing a person)")
    intr = exif_intrinsics(path, obs.size) if photo else None
    if intr is None:
        intr = default_intrinsics(obs.size, options.fov_deg)
    fb = fb if fb is not None else FitBody()
    raw = fit_observations(obs, intr, fb, options.iters, options.warm_iters, options.window, options.fit_shape,
                           options.weights)
    n_missing = int((~obs.found).sum())
    if n_missing:
        logger.warning("%s: no person in %d frame(s): their pose is interpolated (flagged in the motion file)",
                       path, n_missing)
    result = smooth_motion(raw, options.smooth_sigma)
    return FitOutput(raw, result, place_in_world(result, fb, fps), fps, obs.masks)


def _chunks(frames: Iterator[torch.Tensor], n: int) -> Iterator[torch.Tensor]:
    buf = []
    for f in frames:
        buf.append(f)
        if len(buf) == n:
            yield torch.stack(buf)
            buf = []
    if buf:
        yield torch.stack(buf)


def write_preview(path: str | Path, source: str | Path, result: FitResult, fb: FitBody, fps: float) -> Path:
    """Write the fitted mesh over the source's frames: a PNG for a photo, a video otherwise."""
    from ..io import VideoWriter, write_image
    from .preview import chunk_frames, overlay_frames

    path = Path(path)
    frames, _, photo = media_frames(source)
    if path.suffix.lower() == ".png":
        first = next(frames)[None]
        write_image(path, overlay_frames(first, result, fb)[0].permute(1, 2, 0), srgb=False)
        return path
    with VideoWriter(path, fps=fps) as w:
        t = 0
        for chunk in _chunks(frames, chunk_frames(result.size)):
            for img in overlay_frames(chunk, result, fb, start=t):
                w.write(img.mul_(255).round_().to(torch.uint8).permute(1, 2, 0).numpy())  # in place: 12.5 MP
            t += chunk.shape[0]
    return path


def write_fit_masks(path: str | Path, result: FitResult, fb: FitBody, fps: float) -> Path:
    """Write the fitted body's silhouettes in the input's camera: a PNG (photo) or a mask video.

    The frames are rasterized a few at a time (:func:`~relightnet.fit.preview.chunk_frames`), never all at once.
    """
    from ..io import VideoWriter, write_image
    from .preview import chunk_frames, fit_silhouettes

    path = Path(path)
    T, n = result.pose.shape[0], chunk_frames(result.size)

    def rgb(a: int) -> torch.Tensor:  # (B, H, W, 3) uint8 silhouettes of frames [a, a + n)
        masks = fit_silhouettes(result, fb, start=a, stop=min(a + n, T))
        return (masks > 0.5).to(torch.uint8).mul(255)[..., None].expand(-1, -1, -1, 3)

    if path.suffix.lower() == ".png":
        write_image(path, rgb(0)[0].contiguous(), srgb=False)
        return path
    with VideoWriter(path, fps=fps, gray=True) as w:  # .mkv: one plane, half ffv1's memory at 12.5 MP
        for a in range(0, T, n):
            for m in rgb(a):
                w.write(m.contiguous().numpy())
    return path


def motion_for_avatar(source: str | Path, options: FitOptions = FitOptions()) -> dict:
    """The motion of the person in ``source`` (a video or a photo), for the default avatar: fitted
    (:func:`fit_file`), retargeted to the avatar's body with its feet held
    (:func:`~relightnet.fit.retarget.retarget_motion`); foot skating is logged.

    Returns:
        The avatar body's parameters (``AnnyMotion.body_params()``): pose (T, J, 3), trans (T, 3),
        phenotype (1, 6).
    """
    from .metrics import foot_skating
    from .retarget import to_default_avatar

    fb = FitBody()
    fitted = fit_file(source, options, fb=fb)
    moved = to_default_avatar(fitted.motion, fb)
    with torch.no_grad():  # the whole mesh, a few frames at a time (~1 MB a frame): only the landmarks are kept
        points = []
        for a in range(0, moved.n_frames, _BODY_CHUNK):
            sl = slice(a, a + _BODY_CHUNK)
            out = fb.body(pose=moved.pose[sl], trans=moved.trans[sl], phenotype=moved.phenotype[None])
            points.append(fb.landmarks(out.verts, out.joints))
        skate = foot_skating(torch.cat(points))
    logger.info("%s: fitted %d frame(s) in %.1f s; retargeted to the avatar, foot skating %.1f mm/frame", source,
                moved.n_frames, fitted.raw.seconds, skate)
    return moved.body_params()
