"""The demo's motion transfer: a generated source person walks, the avatar performs the walk in the target.

The source is made here, so that its true motion is known: Anny in the ``dress`` outfit (a
different-looking person from the avatar) walks in place, turned 30° from the camera, over the
generator's procedural background, lit by a key light plus ambient. The job then runs as
``avatar --motion-from source.mp4`` does (the shipped segmentation finds the landmarks,
:mod:`relightnet.fit` fits Anny to them, the motion is retargeted to the avatar's body with its
feet held) into the demo's target, lit by the light estimated there; ``side_by_side.mp4`` shows
source | result. The fit is compared with the source's true landmarks (PA-MPJPE: after the best
rotation, scale and translation per frame).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError

__all__ = ["walking_source", "motion_transfer_demo", "SOURCE_MIN_SIZE"]

#: The source is rendered at least this many pixels high: the pose model reads a 256² crop, and a
#: smaller person loses its landmarks.
SOURCE_MIN_SIZE = 256


def walking_source(path, size: int, n_frames: int, body, fps: float = 30.0, seed: int = 3) -> dict:
    """Write a video of a dressed Anny walking in place (module docstring); returns its true motion.

    Args:
        path: the video to write (.mp4 or .mkv). size: side of the square frames (≥ 16).
        n_frames: T ≥ 2. body: an AnnyBody. fps: frame rate. seed: draws the walk's free options.

    Returns:
        The motion given to the body: ``{"pose": {bone: (T, 3)}, "trans": (T, 3)}``.
    """
    from ..color import linear_to_srgb
    from ..data.backgrounds import procedural_background
    from ..io import VideoWriter
    from ..light import ambient_light, directional_light
    from ..prt import PrtSettings
    from ..raster import default_camera
    from ..render.jobs import render_body_frames
    from .outfits import dressed_body

    if n_frames < 2 or size < 16:
        raise InputError(f"walking source: need n_frames >= 2 and a size of at least 16, got {n_frames}, {size}")
    motion = _walk(n_frames, fps, seed)
    dressed = dressed_body(body, "dress")
    light = ambient_light(0.3) + directional_light(torch.tensor([1.0, 0.4, -0.6]), 2.2)
    bg, _ = procedural_background(np.random.default_rng(seed), size, 0.25)
    frames = render_body_frames(dressed, motion, light, dressed.albedo, camera=default_camera((size, size)),
                                n_frames=n_frames, prt=PrtSettings(n_dirs=32), visible_only=True)
    with VideoWriter(path, fps=fps) as v:
        for fr in frames:
            a = fr.render.alpha[0][..., None]
            img = fr.render.image[0] + bg[:size, :size] * (1 - a)
            v.write((linear_to_srgb(img.clamp(0, 1)) * 255).round().to(torch.uint8).numpy())
    return motion


def _walk(n_frames: int, fps: float, seed: int) -> dict:
    from ..body import make_motion

    return make_motion("walk", n_frames, fps=fps, seed=seed, heading=math.radians(30.0))


def motion_transfer_demo(out_dir, target, target_masks, plate, size: int, n_frames: int, body, model,
                         n_dirs: int = 64, fps: float = 30.0, progress: bool = True) -> dict:
    """The demo's ``motion/`` step (module docstring): ``source.mp4``, ``avatar.mp4`` in the target,
    ``side_by_side.mp4`` (source | avatar), and the fit's PA-MPJPE against the source's truth.

    Args:
        out_dir: folder to write into. target, target_masks, plate: the demo's target clip, its
            masks and clean plate. size: the target's side; the source is at least
            :data:`SOURCE_MIN_SIZE`. n_frames: T. body: an AnnyBody. model: the CNN or a predictor.

    Returns:
        Paths by name and ``fit_pa_mpjpe_mm``: the fit against the source's true landmarks (mm,
        after the best rotation, scale and translation per frame).
    """
    from ..fit import FitBody, fit_file, pa_mpjpe, to_default_avatar
    from ..io import write_side_by_side
    from ..prt import PrtSettings
    from .avatar import avatar
    from .settings import AvatarLook, AvatarPlacement

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    source = out / "source.mp4"
    truth = walking_source(source, max(size, SOURCE_MIN_SIZE), n_frames, body, fps)
    fb = FitBody(body)
    fitted = fit_file(source, fb=fb)
    res = avatar(target, out / "avatar.mp4", model=model, motion=to_default_avatar(fitted.motion, fb).body_params(),
                 look=AvatarLook(body=body), target_masks=target_masks, placement=AvatarPlacement(plate=plate),
                 prt=PrtSettings(n_dirs=n_dirs), progress=progress)
    sbs = write_side_by_side(out / "side_by_side.mp4", [source, res.video], fps)
    with torch.no_grad():
        true_out = body(truth)
        true_pts = fb.landmarks(true_out.verts, true_out.joints)
        fit_out = body(**fitted.motion.body_params())
        fit_pts = fb.landmarks(fit_out.verts, fit_out.joints)
    err = float(pa_mpjpe(fit_pts, true_pts, fb.landmarks.mapped).mean())
    return {"motion_source": source, "motion_avatar": res.video, "motion_side_by_side": sbs, "fit_pa_mpjpe_mm": err}
