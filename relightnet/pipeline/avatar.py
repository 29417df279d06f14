"""Job 3 of the pipeline: put a relit avatar into a target video (the 3D path).

Two streaming passes over the target video, so memory does not grow with its length:

1. **Light.** The CNN estimates the SH light of every frame from the person in it (masks
   given, or found by the person segmentation or the model's mask head). The per-frame estimates are smoothed over
   time (default: robust Hermite splines with 3-MAD outlier correction and light-switch
   detection, :func:`relightnet.temporal.smooth_lights`). ``light=`` skips this pass.
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

import json
import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, ShapeError, check_finite, sh_order_from_count
from ..io import VideoWriter, atomic_write, count_frames, read_video, video_info
from ..io.image import linear_to_srgb
from ..raster import Camera, default_camera, silhouette_pixels
from ..raster import antialias as aa
from ..render.jobs import frame_slice, render_body_frames
from ..sh.io import save_light_sequence
from ..temporal.smoothers import SMOOTHING
from .backends import as_predictor
from .scene import avatar_albedo, load_body, open_motion

logger = logging.getLogger(__name__)

__all__ = ["SMOOTHING", "AvatarResult", "estimate_video_lights", "estimate_video_evidence", "smooth_video_lights",
           "avatar"]


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


@torch.no_grad()
def estimate_video_lights(model, video, masks=None, progress: bool = True, mask_source: str = "segment"
                          ) -> torch.Tensor:
    """Per-frame light estimates of a video (the first pass of :func:`avatar`).

    Args:
        model: a :class:`~relightnet.model.RelightNet` or a predictor (:mod:`.backends`).
        video: the target video file.
        masks: folder of mask images or a mask video (one per frame), or None: ``mask_source``
            (``segment``: the person segmentation; ``head``: the model's mask head).

    Returns:
        (T, K, 3) raw lights, camera-relative light frame, linear RGB.
    """
    return estimate_video_evidence(model, video, masks, progress, mask_source)[0]


@torch.no_grad()
def estimate_video_evidence(model, video, masks=None, progress: bool = True, mask_source: str = "segment"):
    """Per-frame lights of a video with the light solve's evidence (for pooling over shots).

    Same arguments as :func:`estimate_video_lights`.

    Returns:
        ``(raw (T, K, 3), evidence, prior)``: the per-frame :class:`~relightnet.model.light_solve.Evidence`
        (``M`` (T, 3, K, K), ``r`` (T, 3, K)) and priors (T, K, 3) — None for a network that
        regresses its light (and the prior None for ``light_mode="solve"``).
    """
    from tqdm import tqdm

    from ..model.light_solve import Evidence
    from ..segment.sources import video_masks

    predict = as_predictor(model)
    if masks is None and mask_source == "head" and not predict.has_mask_head:
        raise InputError("--mask-source head: this model has no mask head; give --target-masks or use 'segment'")
    info, _, frames = video_masks(video, masks, mask_source)
    lights, Ms, rs, priors = [], [], [], []
    for _, img, mask in tqdm(frames, total=info.n_frames or None, desc="estimate light",
                             unit="frame", disable=not progress):
        light, ev, prior = predict.light_evidence(img, mask)
        lights.append(light.float().cpu())
        if ev is not None:
            Ms.append(ev[0][0].float().cpu())
            rs.append(ev[1][0].float().cpu())
        if prior is not None:
            priors.append(prior.float().cpu())
    if not lights:
        raise InputError(f"{video}: the video has no frames")
    ev = Evidence(torch.stack(Ms), torch.stack(rs)) if Ms else None
    return torch.stack(lights), ev, (torch.stack(priors) if priors else None)


def smooth_video_lights(raw: torch.Tensor, method: str = "auto", evidence=None, prior=None, reg: float = 1e-2,
                        fps: float = 30.0):
    """Smooth (T, K, 3) lights over time: returns (smoothed, outliers (T,), switches (T,)).

    ``pooled`` shares the light across frames: the per-frame evidence of the light solve
    (``evidence``, ``prior`` from :func:`estimate_video_evidence`, ``reg`` the network's λ) of the
    frames within :data:`~relightnet.temporal.pooling.POOL_SECONDS` (triangular weights, at the
    video's ``fps``) and between the same detected light switches is solved jointly
    (:func:`relightnet.temporal.pool_shot_lights`); ``hermite``/``poly``/``savgol`` use
    :func:`relightnet.temporal.smooth_lights` with 3-MAD outlier correction and automatic switch
    detection; ``auto`` is ``pooled`` when there is evidence, else ``hermite``; ``none`` returns
    the raw lights.
    """
    from ..temporal import pool_shot_lights, pool_window, smooth_lights

    method = resolve_smoothing(method, evidence is not None)
    none = torch.zeros(raw.shape[0], dtype=torch.bool)
    if method == "pooled":
        if evidence is None:
            raise InputError("smoothing pooled: the model regresses its light (no solve to pool); "
                             "use hermite, poly, savgol or none")
        pooled, _, switches = pool_shot_lights(evidence, prior, reg, window=pool_window(fps))
        return pooled, none, switches
    if method == "none" or raw.shape[0] < 3:
        return raw.clone(), none, none
    res = smooth_lights(raw, method, outlier_eps="3mad", switches="auto")
    return res.smoothed, res.outliers, res.switches


def resolve_smoothing(method: str, has_evidence: bool) -> str:
    """The smoothing ``method`` actually used: ``auto`` is ``pooled`` for a model that solves its
    light (``has_evidence``), else ``hermite``; other names are checked and returned."""
    if method not in SMOOTHING:
        raise InputError(f"smoothing: expected one of {', '.join(SMOOTHING)}, got {method!r}")
    if method == "auto":
        return "pooled" if has_evidence else "hermite"
    return method


def _fingerprint(video, masks, predictor_name: str, mask_source: str = "segment") -> str:
    def stat(p):
        p = Path(p)
        if p.is_dir():
            return sorted((f.name, f.stat().st_size, f.stat().st_mtime_ns) for f in p.iterdir())
        st = p.stat()
        return [p.name, st.st_size, st.st_mtime_ns]

    return json.dumps({"video": stat(video), "masks": mask_source if masks is None else stat(masks),
                       "model": predictor_name}, sort_keys=True)


def _plate_frames(plate, target, size):
    """uint8 (H, W, 3) frames to composite over: the target's, a clean-plate video's, or one image."""
    import itertools

    if plate is None:
        return read_video(target)
    p = Path(plate)
    if p.suffix.lower() in (".png", ".jpg", ".jpeg"):
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


def _reuse(path: Path, fingerprint: str):
    """``(raw, evidence, prior)`` saved by an earlier run with the same inputs, or None."""
    from ..model.light_solve import Evidence

    if not path.is_file():
        return None
    from ..io.arrays import read_npz

    try:  # a damaged or foreign file is not reused (it is rewritten)
        z = read_npz(path, "light estimates", ("fingerprint", "raw", "evidence_M", "evidence_r", "prior"))
    except InputError:
        return None
    if not ("raw" in z and "fingerprint" in z and z["fingerprint"].size == 1 and str(z["fingerprint"]) == fingerprint
            and z["raw"].dtype.kind == "f" and z["raw"].ndim == 3):
        return None
    raw = torch.from_numpy(z["raw"])
    t, k = raw.shape[:2]
    ev = prior = None
    if "evidence_M" in z and "evidence_r" in z:
        M, r = z["evidence_M"], z["evidence_r"]
        if M.shape != (t, 3, k, k) or r.shape != (t, 3, k) or M.dtype.kind != "f" or r.dtype.kind != "f":
            return None
        ev = Evidence(torch.from_numpy(M), torch.from_numpy(r))
    if "prior" in z:
        if z["prior"].shape != raw.shape or z["prior"].dtype.kind != "f":
            return None
        prior = torch.from_numpy(z["prior"])
    return raw, ev, prior


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
    uint8 elsewhere. Only the covered pixels are converted; the same bytes as compositing the
    whole float frame (fg·α + bg·(1−α)) and quantising it."""
    pix = r.frags.pix
    fg = r.image.reshape(-1, 3).index_select(0, pix)
    fg = (linear_to_srgb(fg.clamp(0, 1)).clamp(0, 1) * 255).round().to(torch.uint8)
    out = torch.from_numpy(np.array(bg, dtype=np.uint8, copy=True))
    out.view(-1, 3).index_copy_(0, pix, fg)
    return out.numpy()


def _count_frames(video) -> int:
    """Frames of a video: from the container, else by decoding it (streaming)."""
    return count_frames(video)


@torch.no_grad()
def avatar(
    target,
    out,
    model=None,
    motion="walk",
    body="anny",
    albedo="default",
    target_masks=None,
    plate=None,
    light: torch.Tensor | None = None,
    camera: Camera | None = None,
    smoothing: str = "auto",
    n_dirs: int = 64,
    occlusion: bool = True,
    bounces: int = 0,
    antialias: bool = False,
    model_name: str = "model",
    progress: bool = True,
    mask_source: str = "segment",
) -> AvatarResult:
    """Render an avatar into a target video, lit by the target's (estimated, smoothed) light.

    Args:
        target: target video file (its frame rate, size and sound are kept).
        out: output video (.mp4/.mkv), written atomically; side files next to it (module docstring).
        model: a :class:`~relightnet.model.RelightNet` or a predictor; needed unless ``light`` is given.
        motion: a motion preset (``walk``, ``turn``, ``idle``, ``arm_raise``; made as long as the
            video), an SMPL motion file (.npz, with an SMPL ``body``) or body parameters with a
            leading frame axis.
        body: ``"anny"``, ``"smpl:PATH"`` or a body model.
        albedo: ``"default"``, a texture image path (sRGB, in the body's UV layout), a (V, 3)
            per-vertex albedo or a :class:`~relightnet.render.TexturedAlbedo`.
        target_masks: masks of the person in the target (folder or mask video); None: ``mask_source``.
        plate: what to composite over: None (the target's frames), a clean-plate video of the
            same size (the scene without the person) or one image.
        light: (K, 3) or (T, K, 3) camera-relative light; skips the estimation pass.
        camera: the avatar's camera (default: :func:`~relightnet.raster.default_camera` at the
            video's size: full body, standing at the origin).
        smoothing: one of :data:`SMOOTHING`.
        n_dirs, occlusion, bounces: PRT options.
        antialias: smooth the avatar's silhouette against the background (analytic edge
            antialiasing at the silhouette pixels; about 24 ms per 512² frame).
        model_name: names the model in the resume fingerprint (e.g. the checkpoint path).
        mask_source: without ``target_masks``: ``segment`` (the person segmentation) or ``head``
            (the model's mask head); :mod:`relightnet.segment.sources`.

    Returns:
        :class:`AvatarResult`.
    """
    from tqdm import tqdm

    from ..temporal.plot import light_curves_png

    out = Path(out)
    if out.suffix.lower() not in (".mp4", ".mkv"):
        raise InputError(f"{out}: expected an .mp4 or .mkv output path")
    if smoothing not in SMOOTHING:
        raise InputError(f"smoothing: expected one of {', '.join(SMOOTHING)}, got {smoothing!r}")
    info = video_info(target)
    h, w = info.size
    body_model = load_body(body)
    tex = avatar_albedo(body_model, albedo)
    # A bad motion fails now, not after the light pass; a motion file or mapping is read once, here.
    motion_frames = open_motion(motion, body_model, info.fps)
    backgrounds = _plate_frames(plate, target, info.size)  # likewise a bad plate (frames are read lazily)
    lights_file, plot = _side_paths(out)
    reused = False
    raw = outliers = switches = ev = prior = None
    if light is None:
        if model is None:
            raise InputError("model: give a model (or predictor) to estimate the light, or a light")
        predict = as_predictor(model)
        fp = _fingerprint(target, target_masks, model_name, mask_source)
        cached = _reuse(lights_file, fp)
        reused = cached is not None
        if reused:
            logger.info("reusing the light estimates in %s", lights_file)
        raw, ev, prior = cached if reused else estimate_video_evidence(predict, target, target_masks, progress,
                                                                       mask_source)
        n = raw.shape[0]
        smoothing = resolve_smoothing(smoothing, ev is not None)  # the file and plot name what was used
        smoothed, outliers, switches = smooth_video_lights(raw, smoothing, ev, prior, predict.solve_reg, info.fps)
    else:
        fp = ""
        n = _count_frames(target)
        smoothed = _given_light(light, n)
    params, n_motion = motion_frames(n)  # a preset is made as long as the video
    if n_motion < n:
        logger.warning("the motion has %d frames, the target %d: writing %d frames", n_motion, n, n_motion)
    n = min(n, n_motion)
    smoothed = smoothed[:n]
    camera = default_camera((h, w)) if camera is None else camera
    if tuple(camera.size) != (h, w):
        raise InputError(f"camera: its image size {tuple(camera.size)} differs from the target video's {(h, w)}")

    out.parent.mkdir(parents=True, exist_ok=True)
    arrays = {"smoothed": smoothed.numpy(), "fingerprint": np.array(fp)}
    if raw is not None:
        arrays.update(raw=raw.numpy(), outliers=outliers.numpy(), switches=switches.numpy(),
                      smoothing=np.array(smoothing))
    if ev is not None:
        arrays.update(evidence_M=ev[0].numpy(), evidence_r=ev[1].numpy())
    if prior is not None:
        arrays.update(prior=prior.numpy())
    # the light-sequence format (sh = the light each frame is rendered with), readable by smooth-light
    save_light_sequence(lights_file, smoothed, **arrays)
    png = light_curves_png(raw[:n] if raw is not None else None, smoothed,
                           outliers=outliers[:n] if outliers is not None else None,
                           switches=switches[:n] if switches is not None else None,
                           title=f"{Path(target).name}: light of the target, {smoothing}")
    with atomic_write(plot) as f:
        f.write(png)

    params = frame_slice(params, 0, n, n_motion)  # a motion longer than the video is cut
    frames = render_body_frames(body_model, params, smoothed, tex, camera=camera, n_dirs=n_dirs,
                                occlusion=occlusion, bounces=bounces, n_frames=n, visible_only=True)
    written = 0
    with VideoWriter(out, fps=info.fps, srgb=False, audio_from=target) as writer:
        pairs = zip(backgrounds, frames, strict=False)
        for bg, fr in tqdm(pairs, total=n, desc="avatar", unit="frame", disable=not progress):
            if written == n:
                break
            r = fr.render
            if antialias:
                a = r.alpha[0][..., None]
                bgf = torch.from_numpy(bg).float() / 255
                comp = linear_to_srgb(r.image[0].clamp(0, 1)) * a + bgf * (1 - a)
                smooth = aa(comp[None], r.frags, camera.transform(fr.verts), body_model.faces)[0]
                comp = torch.where(silhouette_pixels(a[..., 0] > 0)[..., None], smooth, comp)
                writer.write(comp)
            else:
                writer.write(_composite_covered(r, bg))
            written += 1
        if written < n:
            raise InputError(f"{plate or target}: only {written} frames decoded, {n} expected")
    logger.info("wrote %s (%d frames), %s, %s", out, written, lights_file, plot)
    return AvatarResult(written, out, lights_file, plot, raw, smoothed, reused, outliers, switches)
