"""``relightnet demo``: the most complete job available, on embedded defaults only.

It uses only what ships with the package (the CC0 env maps, Anny, the pretrained CNN):

1. ``lights/<preset>.png``: a preview of every preset light;
2. ``estimate/``: a synthetic target photo of a person under a held-out light (``night`` or
   ``sunrise``, made by the data generator), the light the CNN estimates from it, and the
   Anny avatar rendered with PRT under the true and under the estimated light, side by side;
3. ``avatar_walk.mp4``: the avatar walking under the estimated light turning about it.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import torch

logger = logging.getLogger(__name__)

__all__ = ["run_demo"]


def _exposed(img: torch.Tensor, scale: float) -> torch.Tensor:
    return (img * scale).clamp(0, 1)


def run_demo(out_dir="out/demo", size: int = 256, frames: int = 48, n_dirs: int = 64) -> dict:
    """Write the demo outputs into ``out_dir``; returns the paths written by name."""
    from ..body import AnnyBody, default_albedo, make_motion
    from ..data import SynthConfig, generate_sample
    from ..io import VideoWriter, write_image
    from ..model import estimate_light, load_model
    from ..render import TexturedAlbedo, render_body_frames
    from ..sh import light_preview, render_presets, rotate_sh_up
    from ..sh.visualize import auto_exposure

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths: dict = {"lights": render_presets(out / "lights", size=size // 2)}

    body = AnnyBody()
    # 1. A target photo with exact ground truth, under a light the CNN never saw in training.
    sample = generate_sample(SynthConfig(res=size, n_dirs=128), "test", 0, body=body)
    photo = torch.from_numpy(sample.arrays["image_srgb"]).permute(2, 0, 1)
    mask = torch.from_numpy(sample.arrays["mask"])
    true_light = torch.from_numpy(sample.arrays["light"])
    model = load_model()
    est = estimate_light(model, photo, mask)
    logger.info("target light source: %s", sample.meta.get("light", {}).get("source", "?"))

    # 2. The avatar under the true and the estimated light (same exposure for both).
    alb = default_albedo(body)
    tex = TexturedAlbedo(alb.texture, body.uv, body.uv_faces)
    pose = {"pose": body.pose("arms_crossed")}
    renders = []
    for light in (true_light, est):
        fr = next(render_body_frames(body, pose, light, tex, size=size, n_dirs=n_dirs))
        renders.append(fr.render)
    scale = auto_exposure(renders[0].image[0], renders[0].alpha[0] > 0)
    est_dir = out / "estimate"
    est_dir.mkdir(exist_ok=True)
    paths["target"] = write_image(est_dir / "target_photo.png", photo.permute(1, 2, 0))
    paths["avatar_true_vs_estimated"] = write_image(
        est_dir / "avatar_true_vs_estimated_light.png",
        torch.cat([_exposed(r.image[0], scale) for r in renders], 1),
    )
    paths["lights_true_vs_estimated"] = write_image(
        est_dir / "light_true_vs_estimated.png",
        torch.cat([light_preview(true_light, 128), light_preview(est, 128)], 0),
    )

    # 3. A walk under the estimated light turning once about the up axis.
    motion = make_motion("walk", frames, seed=0)
    lights = torch.stack([rotate_sh_up(est, 2 * math.pi * t / frames) for t in range(frames)])
    with VideoWriter(out / "avatar_walk.mp4", fps=24) as w:
        for fr in render_body_frames(body, motion, lights, tex, size=size, n_dirs=n_dirs):
            w.write(_exposed(fr.render.image[0], scale))
    paths["walk"] = out / "avatar_walk.mp4"
    return paths
