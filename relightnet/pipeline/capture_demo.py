"""The demo's capture step: a generated person captured under one light performs in the target under another.

The source is made here, so that the person's true albedo is known: a bare Anny with a generated
look (:func:`relightnet.capture.truth.turning_person`) turns once in front of the camera under a
warm light from the left. ``relightnet capture`` makes it an avatar file, and ``avatar --avatar``
lets the captured person walk in the demo's target, lit by the light estimated there. Beside it,
the ground truth: the same generated person (true texture and shape) walking the same walk under the
target's *true* light. ``side_by_side.mp4`` shows source | captured avatar in the target | truth.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import torch

__all__ = ["capture_demo"]

#: The source person's seed (a look and a shape no test uses).
SOURCE_SEED = 23


def _frames_psnr(a: Path, b: Path) -> float:
    """PSNR (dB, 8-bit) between two videos of the same size over their common frames."""
    from ..io import read_video

    sq = n = 0.0
    for x, y in zip(read_video(a), read_video(b), strict=False):
        d = x.astype(np.float64) - y.astype(np.float64)
        sq, n = sq + float(np.square(d).sum()), n + d.size
    return 10 * math.log10(255.0 ** 2 / max(sq / max(n, 1), 1e-12))


def capture_demo(out_dir, target, target_masks, plate, true_light: torch.Tensor, size: int, n_frames: int, body,
                 model, n_dirs: int = 64, fps: float = 30.0, progress: bool = True) -> dict:
    """The demo's ``capture/`` step (module docstring).

    Args:
        out_dir: folder to write into. target, target_masks, plate: the demo's target clip, masks and clean plate.
        true_light: (T, K, 3) the target's true light per frame (camera-relative). size: the target's side; the
            source is rendered at least 256 px (the pose model's input). n_frames: T. body: an AnnyBody.
        model: the CNN's predictor.

    Returns:
        Paths by name, ``capture_seen_share``, ``capture_albedo_error`` (relative RMSE over the texels seen,
        :func:`relightnet.capture.metrics.albedo_error`) and ``capture_psnr_db``: the captured avatar in the target
        against the truth there (whole frames, 8-bit).
    """
    from ..capture.metrics import albedo_error
    from ..capture.texture import TextureOptions
    from ..capture.truth import light_pair, turning_person
    from ..fit import FitOptions
    from ..io import write_side_by_side
    from ..prt import PrtSettings
    from ..render.frame import TexturedAlbedo
    from .avatar import avatar
    from .capture_job import CaptureOptions, capture_file
    from .scene import open_motion
    from .settings import AvatarLook, AvatarPlacement

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    src_size = max(size, 256)
    truth = turning_person(out / "source", body, light_pair()[0], n_frames=n_frames, size=(src_size, src_size),
                           seed=SOURCE_SEED, texture_size=512, fps=fps)
    # The source's camera is the default one (35°): given, as a user gives --fov for a lens they know.
    rep = capture_file(truth.video, out / "person.avatar.npz", model,
                       CaptureOptions(texture=TextureOptions(size=512, n_dirs=n_dirs), fit=FitOptions(fov_deg=35.0)))
    moved = avatar(target, out / "avatar.mp4", model=model, motion="walk", look=AvatarLook(body=body, captured=rep.out),
                   target_masks=target_masks, placement=AvatarPlacement(plate=plate), prt=PrtSettings(n_dirs=n_dirs),
                   progress=progress)
    params, _ = open_motion("walk", body, fps)(n_frames)
    params = dict(params, phenotype=truth.params["phenotype"])
    true = avatar(target, out / "truth.mp4", motion=params,
                  look=AvatarLook(body=body, albedo=TexturedAlbedo(truth.texture, body.uv, body.uv_faces)),
                  placement=AvatarPlacement(plate=plate), prt=PrtSettings(n_dirs=n_dirs), progress=progress,
                  light=true_light[:n_frames])
    sbs = write_side_by_side(out / "side_by_side.mp4", [truth.video, moved.video, true.video], fps)
    err = albedo_error(rep.avatar.texture, truth.texture, rep.seen)
    return {"capture_source": truth.video, "capture_avatar_file": rep.out, "capture_avatar": moved.video,
            "capture_truth": true.video, "capture_side_by_side": sbs, "capture_seen_share": rep.avatar.seen_share,
            "capture_albedo_error": err, "capture_psnr_db": _frames_psnr(moved.video, true.video)}
