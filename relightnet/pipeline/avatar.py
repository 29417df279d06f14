"""Job 3 of the pipeline: put a relit avatar into a target video (the 3D path).

Two streaming passes over the target video, so memory does not grow with its length:

1. **Light.** The CNN estimates the SH light of every frame from the person in it (masks
   given, or found by the person segmentation or the model's mask head). The per-frame
   estimates are smoothed over time (:func:`~relightnet.temporal.smooth_video_lights`;
   default ``auto``: the shot's evidence pooled for a network that solves its light, else robust
   Hermite splines with 3-MAD outlier correction and light-switch detection). ``light=`` skips
   this pass.
2. **Render.** The avatar (Anny or SMPL, posed by a motion) is rendered each frame with
   PRT transport (cosine × visibility by ray casting, optional interreflection) under that
   frame's smoothed light, and composited over the target frame.

The light is camera-relative (the light frame of the target camera), and the avatar is
rendered with the same camera-relative light, so it is lit as if it stood in the target
scene seen by the target camera. The light's scale is the CNN's: the avatar gets the
target video's exposure without any matching.

Side outputs next to ``OUT.mp4``: ``OUT.lights.npz``, a light-sequence file
(:func:`relightnet.sh.save_light_sequence`: ``sh`` the smoothed light of each frame, which
``relightnet smooth-light`` and ``--light`` read; raw and smoothed lights, outliers,
switches, and a fingerprint of the inputs — when it matches, a rerun reuses the raw
estimates instead of running the CNN again) and ``OUT.lights.png`` (light curves).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, ShapeError, check_finite, sh_order_from_count
from ..io import PHOTO_SUFFIXES, VideoWriter, count_frames, read_video, video_info
from ..io.hdr_video import HdrClip, HdrVideoWriter
from ..io.video import frame_times
from ..names import VIDEO_SMOOTHING
from ..prt import PrtSettings
from ..raster import Camera, default_camera
from ..raster.antialias import antialias_pixels, silhouette_pixels
from ..render.jobs import frame_slice, render_body_frames
from ..temporal.registry import check_smoothing, smooth_video_lights
from .backends import as_predictor
from .clean_plate import check_camera_start, stand_in_frames
from .outfits import avatar_look
from .scene import load_body, open_motion
from .settings import AvatarLook, AvatarPlacement, VideoLightSettings
from .video_lights import (
    VideoEstimates,
    estimate_video_evidence,
    lights_fingerprint,
    read_light_estimates,
    write_video_lights,
)

logger = logging.getLogger(__name__)


__all__ = ["AvatarResult", "avatar"]


@dataclass(frozen=True, eq=False)
class AvatarResult:
    """What :func:`avatar` wrote: frame count, paths, the lights (T, K, 3) and the frames flagged as
    outliers / light switches (T,) by the smoothing (raw, outliers, switches are None with a given light)."""

    n_frames: int
    video: Path
    lights_file: Path
    plot: Path | None
    lights_raw: torch.Tensor | None
    lights_smoothed: torch.Tensor
    reused_estimates: bool = False
    outliers: torch.Tensor | None = None
    switches: torch.Tensor | None = None


@dataclass(frozen=True, eq=False)
class _TargetLight:
    """The estimate and smooth stages' result: lights (T, K, 3) for the target's frames."""

    smoothed: torch.Tensor
    estimates: VideoEstimates | None = None  # the CNN's, per frame
    outliers: torch.Tensor | None = None
    switches: torch.Tensor | None = None
    fingerprint: str = ""
    reused: bool = False
    method: str = ""  # the smoothing used (``auto`` resolved)

    @property
    def raw(self) -> torch.Tensor | None:
        """(T, K, 3) the CNN's per-frame lights, or None (a light given)."""
        return None if self.estimates is None else self.estimates.raw


def _plate_frames(plate, target, size):
    """uint8 (H, W, 3) frames to composite over: the target's, a clean-plate video's, or one image."""
    import itertools

    if plate is None:
        return read_video(target)
    p = Path(plate)
    if p.suffix.lower() in PHOTO_SUFFIXES:
        from ..io import read_image

        if not p.is_file():
            raise InputError(f"--plate {plate}: image not found")
        img = (read_image(p) * 255).round().to(torch.uint8).numpy()
        if img.shape[:2] != tuple(size):
            raise InputError(f"--plate {plate}: size {img.shape[:2]} differs from the target's {tuple(size)}")
        return itertools.repeat(img)
    if video_info(p).size != tuple(size):
        raise InputError(f"--plate {plate}: size {video_info(p).size} differs from the target's {tuple(size)}")
    return read_video(p)


def _backgrounds(plate, target, size, replace_person: bool, target_masks, mask_source):
    """:func:`_plate_frames` (a bad plate fails before the light pass: frames are read lazily); with
    ``replace_person``, first the early check that the target's camera is fixed (its first frames:
    :func:`.clean_plate.check_camera_start`)."""
    if replace_person:
        check_camera_start(target, target_masks, mask_source)
    return _plate_frames(plate, target, size)


def _side_paths(out: Path) -> tuple[Path, Path]:
    return out.with_name(out.stem + ".lights.npz"), out.with_name(out.stem + ".lights.png")


def _given_light(light: torch.Tensor, n: int) -> torch.Tensor:
    if light.dim() == 2:
        light = light[None].expand(n, -1, -1)
    if light.dim() != 3 or light.shape[-1] != 3:
        raise ShapeError(f"light: expected (K, 3) or (T, K, 3), got {tuple(light.shape)}")
    if light.shape[0] != n:
        raise InputError(f"light: a light sequence of {light.shape[0]} frames for a {n}-frame target video")
    sh_order_from_count(light.shape[1], "light")
    check_finite(light, "light")
    return light.float()


def _composite_covered(r, bg: np.ndarray) -> np.ndarray:
    """The 8-bit frame: the render's sRGB-encoded pixels where it covers (alpha 1), ``bg`` (H, W, 3)
    uint8 elsewhere (:func:`relightnet.render.shading.composite_covered`). Only the covered pixels are
    converted (a render of a window of the frame lands at the window's place); the same bytes as
    compositing the whole float frame (fg·α + bg·(1−α)) and quantising it."""
    from ..color import linear_to_srgb
    from ..render.shading import composite_covered

    fg = (linear_to_srgb(r.pix_image.clamp(0, 1)).clamp(0, 1) * 255).round().to(torch.uint8)
    bg = np.ascontiguousarray(bg, dtype=np.uint8)  # read only: composite_covered writes into its own copy
    if not bg.flags.writeable:  # torch.from_numpy wants a writable array (a plate repeated, a decoded frame)
        bg = bg.copy()
    return composite_covered(fg, r.frags.region.to_frame(r.frags.pix), torch.from_numpy(bg)).numpy()


def _light_stages(model, target, target_masks, lights: VideoLightSettings, lights_file: Path, fps: float,
                  progress: bool) -> _TargetLight:
    """Stages 1–2, estimate → smooth: the CNN's per-frame lights of the target (reused from
    ``lights_file`` when its fingerprint matches), smoothed over time; with ``lights.plate_light``, each
    smoothed light combined with it (:func:`relightnet.light.combine_person_plate`)."""
    mask_source, smoothing, plate_light = lights.mask_source, lights.smoothing, lights.plate_light
    if model is None:
        raise InputError("model: give a model (or predictor) to estimate the light, or a light")
    predict = as_predictor(model)
    fp = lights_fingerprint(target, target_masks, lights.model_name, mask_source)
    cached = read_light_estimates(lights_file, fp)
    if cached is not None:
        logger.info("reusing the light estimates in %s", lights_file)
    est = cached if cached is not None else estimate_video_evidence(predict, target, target_masks, progress,
                                                                    mask_source)
    # resolved once, there: smoothed with it, recorded as used (a too short clip: none)
    smoothed, outliers, switches, method = smooth_video_lights(est.raw, smoothing, est.evidence, est.prior,
                                                               predict.solve_reg, fps, colour=est.colour)
    if plate_light is not None:
        from ..light.plate import combine_person_plate

        smoothed = combine_person_plate(smoothed, plate_light.light.to(smoothed), plate_light.view)
        method = f"{method}+plate"
    return _TargetLight(smoothed, est, outliers, switches, fp, cached is not None, method)


def _composite_frame(r, bg, antialias: bool, camera: Camera, verts: torch.Tensor, faces: torch.Tensor):
    """Stage 4, composite: the render's sRGB-encoded pixels over the uint8 (H, W, 3) background →
    ((H, W, 3) uint8 (:func:`_composite_covered`), (H, W) bool the pixels drawn); with ``antialias``, the
    silhouette's pixels then get what analytic edge antialiasing of the whole composited frame gives there
    (:func:`relightnet.raster.antialias.antialias_pixels`: the colours of the pixels along the silhouette
    only, no float copy of the frame; a frame at the pixel limit is 150 MB in float). The render may
    be of a window of the frame (``render_body_frames(box=True)``, holding every pixel next to a
    covered one): its images, mask and silhouette are the window's, and only the composite is the
    frame's."""
    from ..color import linear_to_srgb

    out = _composite_covered(r, bg)
    to_frame = r.frags.region.to_frame  # the window's flat pixel indices → the frame's
    drawn = torch.zeros(out.shape[:2], dtype=torch.bool)
    drawn.view(-1)[to_frame(r.frags.pix)] = True
    if not antialias:
        return out, drawn
    flat = torch.from_numpy(out).view(-1, 3)  # the background where not covered

    def color_at(idx):  # fg·α + bg·(1−α) with α in {0, 1}, in [0, 1]
        c = flat[to_frame(idx)].float().div_(255)
        at = r.frags.locate(idx)
        on = at >= 0
        c[on] = linear_to_srgb(r.pix_image[at[on]].clamp(0, 1))
        return c

    sil = silhouette_pixels(r.frags.mask[0])[None]
    idx, colors = antialias_pixels(color_at, r.frags, camera.transform(verts), faces, sil)
    flat[to_frame(idx)] = colors.clamp_(0, 1).mul_(255).round_().to(torch.uint8)
    drawn.view(-1)[to_frame(idx)] = True
    return out, drawn


def _render_stages(out: Path, target, backgrounds, frames, n: int, fps: float, antialias: bool, camera: Camera,
                   faces: torch.Tensor, progress: bool, source, clip: HdrClip | None = None) -> int:
    """Stages 3–5, render → composite → write, streaming, on the target's timeline (its frame times
    and sound): returns the frames written. ``clip``: the target's HDR frames, the composite carried
    over to them (:meth:`~relightnet.io.hdr_video.HdrClip.carry` with the pixels drawn)."""
    from tqdm import tqdm

    times = frame_times(target)  # None: the target states no times, the frames follow at its average rate
    written = 0
    with (VideoWriter(out, fps=fps, srgb=False, audio_from=target) if clip is None else
          HdrVideoWriter(out, clip.fmt, fps=fps, audio_from=target)) as writer:
        pairs = zip(backgrounds, frames, strict=False)
        for bg, fr in tqdm(pairs, total=n, desc="avatar", unit="frame", disable=not progress):
            if written == n:
                break
            time = float(times[written]) if times is not None and written < len(times) else None
            frame, drawn = _composite_frame(fr.render, bg, antialias, camera, fr.verts, faces)
            if clip is not None:
                frame = clip.carry(torch.from_numpy(frame), torch.from_numpy(np.ascontiguousarray(bg)), drawn)
            writer.write(frame, time=time)
            del bg, fr  # the next frame is decoded and rendered without this one's
            written += 1
        if written < n:
            raise InputError(f"{source}: only {written} frames decoded, {n} expected")
    return written


def _motion_for(motion_frames, n: int) -> tuple[dict, int]:
    """The motion's parameters for an n-frame target (a preset is made as long as the video, a
    longer motion is cut, a shorter one shortens the output): (params, frames to write)."""
    params, n_motion = motion_frames(n)
    if n_motion < n:
        logger.warning("the motion has %d frames, the target %d: writing %d frames", n_motion, n, n_motion)
    m = min(n, n_motion)
    return frame_slice(params, 0, m, n_motion), m


def _camera_for(camera: Camera | None, size) -> Camera:
    """The avatar's camera: the default one at the video's size, or the given one if its size matches."""
    camera = default_camera(size) if camera is None else camera
    if tuple(camera.size) != tuple(size):
        raise InputError(f"camera: its image size {tuple(camera.size)} differs from the target video's {tuple(size)}")
    return camera


def _hdr_clip(target, placement: AvatarPlacement) -> HdrClip:
    """``hdr=True``'s checks before any work: the target's own frames behind the avatar, the target HDR."""
    if placement.plate is not None or placement.replace_person:
        raise InputError("--hdr keeps the target's own frames HDR: not with --plate or --replace-person")
    return HdrClip(target)  # an SDR target is refused here


def _check_options(out, smoothing: str) -> Path:
    """The checks that need nothing read: the output's type, the smoothing (--replace-person's exclusions:
    :class:`~relightnet.pipeline.AvatarPlacement`)."""
    out = Path(out)
    if out.suffix.lower() not in (".mp4", ".mkv"):
        raise InputError(f"{out}: expected an .mp4 or .mkv output path")
    check_smoothing(smoothing, VIDEO_SMOOTHING)
    return out


@torch.no_grad()
def avatar(
    target,
    out,
    model=None,
    motion="walk",
    look: AvatarLook = AvatarLook(),
    target_masks=None,
    light: torch.Tensor | None = None,
    lights: VideoLightSettings = VideoLightSettings(),
    prt: PrtSettings = PrtSettings(n_dirs=64),
    placement: AvatarPlacement = AvatarPlacement(),
    progress: bool = True,
    hdr: bool = False,
) -> AvatarResult:
    """Render an avatar into a target video, lit by the target's (estimated, smoothed) light.

    Args:
        target: target video file (its size, frame times and sound are kept: VFR stays VFR, ``io.timestamps``).
        out: output video (.mp4/.mkv), written atomically; side files next to it (module docstring).
        model: a :class:`~relightnet.model.RelightNet` or a predictor; needed unless ``light`` is given.
        motion: a motion preset (``walk``, ``turn``, ``idle``, ``arm_raise``; made as long as the
            video), an SMPL motion file (.npz, with an SMPL ``body``) or body parameters with a
            leading frame axis.
        look: an :class:`~relightnet.pipeline.AvatarLook`: the body, its albedo, an outfit or a
            captured person's avatar file (``relightnet capture``; :func:`.avatar_look`), and the
            silhouette's antialiasing (about 24 ms per 512² frame).
        target_masks: masks of the person in the target (folder or mask video); None: ``lights.mask_source``.
        light: (K, 3) or (T, K, 3) camera-relative light; skips the estimation pass.
        lights: a :class:`~relightnet.pipeline.VideoLightSettings`: the smoothing (one of
            :data:`relightnet.names.VIDEO_SMOOTHING`), the mask source, the model's name in the resume
            fingerprint and a plate light combined with the estimates (``light.combine_person_plate``).
        prt: the PRT options (:class:`~relightnet.prt.PrtSettings`; by default 64 directions).
        placement: an :class:`~relightnet.pipeline.AvatarPlacement`: a clean plate to composite over, the
            avatar's camera, or taking the person's place (:func:`.clean_plate.stand_in`).
        progress: show a tqdm bar.
        hdr: keep an HLG or PQ target HDR: the avatar is composited over the target's own frames read as
            linear light (:func:`relightnet.io.hdr_video.hdr_behind`), written as the target's format
            (:class:`~relightnet.io.hdr_video.HdrVideoWriter`); an SDR target, a plate or
            ``replace_person`` is refused before any work.

    Returns:
        :class:`AvatarResult`.
    """
    smoothing, mask_source, plate = lights.smoothing, lights.mask_source, placement.plate
    out = _check_options(out, smoothing)
    info = video_info(target)
    clip = _hdr_clip(target, placement) if hdr else None
    base, body_model, tex = avatar_look(load_body(look.body), look.albedo, look.outfit, look.captured)
    # A bad motion fails now, not after the light pass; a motion file or mapping is read once, here.
    motion_frames = open_motion(motion, base, info.fps)
    backgrounds = _backgrounds(plate, target, info.size, placement.replace_person, target_masks,
                               mask_source)  # likewise
    lights_file, plot = _side_paths(out)
    if light is None:
        lit = _light_stages(model, target, target_masks, lights, lights_file, info.fps, progress)
        n = lit.raw.shape[0]
    else:
        n = count_frames(target)  # from the container, else by decoding (streaming)
        lit = _TargetLight(_given_light(light, n))
    params, n = _motion_for(motion_frames, n)
    smoothed = lit.smoothed[:n]
    camera = placement.camera
    if placement.replace_person:  # over the clean plate, standing where the person stands in each frame
        backgrounds, camera, params = stand_in_frames(target, out, n, body_model, target_masks, mask_source, params)
    camera = _camera_for(camera, info.size)
    method = lit.method or smoothing  # the file and the plot name the method used
    write_video_lights(lights_file, plot, lit.smoothed, lit.fingerprint, lit.estimates, lit.outliers, lit.switches,
                       method, title=f"{Path(target).name}: light of the target, {method}")
    frames = render_body_frames(body_model, params, smoothed, tex, camera=camera, prt=prt, n_frames=n,
                                visible_only=True, box=True)
    written = _render_stages(out, target, backgrounds, frames, n, info.fps, look.antialias, camera, body_model.faces,
                             progress, plate or target, clip)
    logger.info("wrote %s (%d frames), %s, %s", out, written, lights_file, plot)
    return AvatarResult(written, out, lights_file, plot, lit.raw, smoothed, lit.reused, lit.outliers, lit.switches)
