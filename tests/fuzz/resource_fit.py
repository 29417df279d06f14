"""Resource cases of ``relightnet fit`` and ``avatar --motion-from``: a person's video at the pixel limit.

Part of the resource cases (``resource_cases.CASES`` gathers them). The clip is Anny walking in
place, rendered small (the segmentation needs a person; the renderer at 12.5 MP would take most of
the budget of the process that writes it) and upscaled to 4000 × 3120 (12.48 MP, just under the
limit), over the walking target's textured background. The fit once kept a float mask per frame
at the frame's size (50 MB a frame here); these cases hold it to the 2 GB budget.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from resource_runner import Case  # noqa: E402

sys.path.pop(0)

#: The size the person is rendered at, and the factor it is upscaled by (to 3120 × 4000).
SMALL, UP = (390, 500), 8


def person_clip(path: Path, n: int, small: tuple[int, int] = SMALL, up: int = UP, fps: float = 10.0) -> None:
    """Write an mp4 of ``n`` frames of ``small × up`` pixels: Anny walking in place, facing the camera a quarter
    turned, over a textured background (sRGB, bilinear upscale of the small render)."""
    import torch
    import torch.nn.functional as F

    from relightnet.body import AnnyBody, make_motion
    from relightnet.color import linear_to_srgb
    from relightnet.io import VideoWriter
    from relightnet.light import ambient_light, directional_light
    from relightnet.pipeline.scene import avatar_albedo
    from relightnet.pipeline.walk_target import _background
    from relightnet.prt import PrtSettings
    from relightnet.raster import default_camera
    from relightnet.render.jobs import render_body_frames

    body = AnnyBody()
    motion = make_motion("walk", n, fps=fps, seed=0, heading=math.pi / 6)
    light = ambient_light(0.35) + directional_light(torch.tensor([1.0, 0.5, 0.8]), 2.0)
    bg = _background(small, 0)
    frames = render_body_frames(body, motion, light, avatar_albedo(body), camera=default_camera(small),
                                prt=PrtSettings(n_dirs=64, occlusion=False), n_frames=n, visible_only=True)
    with VideoWriter(path, fps=fps) as w:
        for fr in frames:
            a = fr.render.alpha[0]
            img = linear_to_srgb((fr.render.image[0] + bg * (1 - a[..., None])).clamp(0, 1))
            big = F.interpolate(img.permute(2, 0, 1)[None], scale_factor=up, mode="bilinear", align_corners=False)
            w.write((big[0].permute(1, 2, 0).clamp(0, 1) * 255).round().to(torch.uint8).numpy())
            del big


def fit_at_limit(folder: Path, n: int = 4) -> Case:
    """A person's video of 4000 × 3120 (12.48 MP) fitted, with the fitted masks written: within the budget."""
    person_clip(folder / "clip.mp4", n)
    argv = ["-q", "fit", "clip.mp4", "--out", "motion.npz", "--mask-out", "fitted.mkv", "--iters", "8",
            "--warm-iters", "4", "--threads", "1"]  # the memory is the frames' (segmentation, masks), not the steps'
    return Case(argv, "clip.mp4", expect="ok", outputs=("motion.npz", "fitted.mkv"))


def avatar_motion_from_at_limit(folder: Path) -> Case:
    """``avatar --motion-from`` a 12.5 MP person's video (2 frames: the fit's 120 steps), into a small target:
    within the budget."""
    from resource_media import video

    person_clip(folder / "source.mp4", 2)
    video(folder / "target.mp4", 2)
    argv = ["-q", "avatar", "--motion-from", "source.mp4", "--target", "target.mp4", "--light", "studio",
            "--no-occlusion", "--n-dirs", "16", "--out", "out.mp4"]
    return Case(argv, "source.mp4", expect="ok", outputs=("out.mp4", "out.lights.npz", "out.lights.png"))


#: (Longer clips take minutes on a loaded 2-core machine, past the cases' wall cap: measured in SECURITY.md.)
SLOW = {"fit-12.5MP-4-frames", "avatar-motion-from-12.5MP"}

CASES = {
    "fit-12.5MP-4-frames": fit_at_limit,
    "avatar-motion-from-12.5MP": avatar_motion_from_at_limit,
}
