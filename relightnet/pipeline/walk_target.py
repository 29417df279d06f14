"""A generated target video whose true background is known: a person walking across a static scene.

The clean plate (:mod:`.clean_plate`) is measured on it: Anny walks sideways (heading +x)
across the frame in front of a textured background (the generator's procedural background
times soft vertical and horizontal stripes, so a wrong sample shows), seen by the default
camera and lit by a key light plus ambient. The person's true masks are the renderer's
coverage; the background image is the truth the plate is compared with.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError

__all__ = ["WalkingTarget", "walking_target", "replaced_person_demo"]


@dataclass(frozen=True, eq=False)
class WalkingTarget:
    """What :func:`walking_target` wrote and knows.

    Attributes:
        video: the target video. masks: a mask video (white = person) of the same frames.
        background: (H, W, 3) uint8 the true background (sRGB). n_frames, fps.
        ever: (H, W) bool pixels the person covers in some frame. always: (H, W) bool in every frame.
        path: (T, 3) float32 the person's root translation in every frame (world, metres): the true path.
    """

    video: Path
    masks: Path
    background: np.ndarray
    n_frames: int
    fps: float
    ever: np.ndarray
    always: np.ndarray
    path: np.ndarray


def _background(size, seed: int) -> torch.Tensor:
    """(H, W, 3) linear textured background."""
    from ..data.backgrounds import procedural_background

    H, W = size
    img, _ = procedural_background(np.random.default_rng(seed), max(H, W), 0.25)
    img = img[:H, :W]
    y, x = torch.meshgrid(torch.arange(H, dtype=torch.float32), torch.arange(W, dtype=torch.float32), indexing="ij")
    s = max(H, W) / 256
    stripes = 1 + 0.25 * torch.sin(2 * math.pi * x / (9 * s)) + 0.15 * torch.sin(2 * math.pi * y / (23 * s))
    return (img * stripes[..., None]).clamp(0.01, 1.0)


def walking_target(out_dir, size=(256, 256), n_frames: int = 48, fps: float = 30.0, seed: int = 0,
                   suffix: str = ".mkv", body=None) -> WalkingTarget:
    """Write ``target{suffix}`` and ``masks{suffix}`` into ``out_dir``: Anny walking across a known background.

    Args:
        size: (H, W). n_frames: T (the walk crosses the frame in about 1.6 s, whatever T).
        suffix: ``.mkv`` (lossless ffv1) or ``.mp4``. body: an AnnyBody (made when None).
        The person is shaded without occlusion (cosine transport): only its outline matters here.

    Returns:
        :class:`WalkingTarget`.
    """
    from ..body import AnnyBody, make_motion
    from ..color import linear_to_srgb
    from ..io import VideoWriter
    from ..light import ambient_light, directional_light
    from ..prt import PrtSettings
    from ..raster import default_camera
    from ..render.jobs import render_body_frames
    from .scene import avatar_albedo

    H, W = int(size[0]), int(size[1])
    if n_frames < 2 or H < 16 or W < 16:
        raise InputError(f"walking target: need n_frames >= 2 and a size of at least 16², got {n_frames}, {size}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    body = AnnyBody() if body is None else body
    camera = default_camera((H, W))
    half = 3.0 * math.tan(math.radians(35.0) / 2) * W / H  # half the visible width at z = 0 (metres)
    speed = (2 * half + 0.6) / 1.6  # m/s: crosses the frame in ~1.6 s
    motion = make_motion("walk", n_frames, fps=fps, seed=seed, advance=True, heading=math.pi / 2,
                         stride_length=1.3, freq=speed / 1.3)
    motion["trans"][:, 0] -= half + 0.3  # start just outside the left edge
    if n_frames / fps < 1.6:  # a short clip still crosses: scale the path (the legs slide a little)
        x = motion["trans"][:, 0]
        motion["trans"][:, 0] = x[0] + (x - x[0]) * (1.6 * fps / n_frames)
    light = ambient_light(0.35) + directional_light(torch.tensor([1.0, 0.5, 0.8]), 2.0)
    bg = _background((H, W), seed)
    truth = (linear_to_srgb(bg) * 255).round().clamp(0, 255).to(torch.uint8).numpy()
    ever = np.zeros((H, W), bool)
    always = np.ones((H, W), bool)
    paths = out / f"target{suffix}", out / f"masks{suffix}"
    frames = render_body_frames(body, motion, light, avatar_albedo(body), camera=camera,
                                prt=PrtSettings(n_dirs=64, occlusion=False), n_frames=n_frames, visible_only=True)
    with VideoWriter(paths[0], fps=fps) as v, VideoWriter(paths[1], fps=fps) as vm:
        for fr in frames:
            a = fr.render.alpha[0]
            img = fr.render.image[0] + bg * (1 - a[..., None])
            v.write((linear_to_srgb(img.clamp(0, 1)) * 255).round().to(torch.uint8).numpy())
            m = a.numpy() > 0.5
            ever |= m
            always &= m
            vm.write(np.repeat(m[..., None].astype(np.uint8) * 255, 3, -1))
    path = np.asarray(motion["trans"], dtype=np.float32)[:n_frames]
    return WalkingTarget(paths[0], paths[1], truth, n_frames, fps, ever, always, path)


def replaced_person_demo(out_dir, size: int, n_frames: int, body, n_dirs: int = 64, outfit: str = "casual",
                         progress: bool = True) -> dict:
    """The demo's replaced person: a walking target with a known background (``replace/target.mp4``),
    ``avatar --replace-person --outfit`` on it under the target's light (``replace/avatar.mp4``, the plate
    ``replace/avatar.plate.png``; the person's masks are the generator's, as in the demo's main clip), and the
    plate's PSNR against the true background over the pixels the
    person covered and uncovered. Returns the paths and figures by name."""
    from ..io import read_image
    from ..light import ambient_light, directional_light
    from ..prt import PrtSettings
    from .avatar import avatar
    from .clean_plate import plate_psnr
    from .settings import AvatarLook, AvatarPlacement

    out = Path(out_dir)
    wt = walking_target(out, size=(size, size), n_frames=n_frames, suffix=".mp4", body=body)
    light = ambient_light(0.35) + directional_light(torch.tensor([1.0, 0.5, 0.8]), 2.0)  # the target's own light
    avatar(wt.video, out / "avatar.mp4", light=light, look=AvatarLook(body=body, outfit=outfit), target_masks=wt.masks,
           placement=AvatarPlacement(replace_person=True), prt=PrtSettings(n_dirs=n_dirs), progress=progress)
    plate = (read_image(out / "avatar.plate.png") * 255).round().to(torch.uint8).numpy()
    # Over the pixels the person covered in some frame and uncovered in another (true masks); what the job
    # had to inpaint there (its segmentation masks are dilated) counts against the plate.
    psnr = plate_psnr(plate, wt.background, wt.ever & ~wt.always)
    return {"replace_target": wt.video, "replace_avatar": out / "avatar.mp4", "replace_plate": out / "avatar.plate.png",
            "plate_psnr_db": psnr, "never_uncovered_share": float(wt.always.sum()) / max(int(wt.ever.sum()), 1)}
