"""What a person looks at to judge a capture: the texture, its confidence, and the avatar from four sides.

:func:`preview_sheet` draws one PNG: the captured texture (sRGB), its confidence (grey: sum of the
frames' weights, log-scaled; red: filled from the mirror image; blue: inpainted), and the captured
avatar (offsets and texture) standing in the A-pose, seen from the front, its left, the back and
its right under a neutral light (ambient and a soft light from above the camera).
"""

from __future__ import annotations

import math
from pathlib import Path

import torch
import torch.nn.functional as F

__all__ = ["VIEW_ANGLES", "neutral_light", "turntable_views", "preview_sheet"]

#: The four sides shown, degrees about the vertical axis (0: facing the camera).
VIEW_ANGLES = (0.0, 90.0, 180.0, 270.0)


def neutral_light() -> torch.Tensor:
    """(9, 3) a neutral light: ambient plus a soft white light from above the camera."""
    from ..light import ambient_light, directional_light

    return ambient_light(0.55) + directional_light(torch.tensor([0.0, 0.6, 1.0]), 1.2)


def turntable_views(captured, size: int = 384, angles=VIEW_ANGLES, light: torch.Tensor | None = None
                    ) -> torch.Tensor:
    """(N, size, size·3/4, 3) linear renders of a :class:`~relightnet.capture.CapturedBody` turned by ``angles``
    (degrees) in the A-pose, over black, framed to the person's height."""
    from ..body import pose_preset
    from ..prt import PrtSettings
    from ..raster import default_camera
    from ..render.jobs import render_body_frames

    body = captured.body
    n = len(angles)
    pose = torch.zeros(n, body.num_joints, 3)
    for name, rv in pose_preset("apose").items():
        pose[:, body.joint_index(name)] = torch.tensor(rv)
    pose[:, 0, 1] = torch.tensor([math.radians(a) for a in angles])
    size_hw = (int(size), int(size) * 3 // 4)
    params = {"pose": pose, "trans": torch.zeros(n, 3)}
    with torch.no_grad():
        ys = captured({"pose": pose[:1], "trans": torch.zeros(1, 3)}).verts[0, :, 1]
    top, bottom = float(ys.max()), float(ys.min())
    h = max(top - bottom, 0.3)  # the default camera frames 1.7 m from 3 m: a taller or shorter person alike
    camera = default_camera(size_hw, distance=3.0 * h / 1.7, target=(0.0, (top + bottom) / 2, 0.0))
    frames = render_body_frames(captured, params, neutral_light() if light is None else light, captured.albedo,
                                camera=camera, prt=PrtSettings(n_dirs=64), visible_only=True)
    return torch.stack([f.render.image[0] for f in frames])


def _confidence_image(avatar, size: int) -> torch.Tensor:
    """(size, size, 3) linear: log-scaled confidence in grey, mirrored texels red, inpainted blue."""
    c = avatar.confidence
    g = (torch.log1p(c) / max(float(torch.log1p(c).max()), 1e-6)).clamp(0, 1)
    img = g[..., None].expand(-1, -1, 3).clone()
    img[avatar.filled == 1] = torch.tensor([0.6, 0.05, 0.05])
    img[avatar.filled == 2] = torch.tensor([0.05, 0.1, 0.6])
    return _resize(img, size)


def _resize(img: torch.Tensor, size: int) -> torch.Tensor:
    return F.interpolate(img.permute(2, 0, 1)[None], size=(size, size), mode="area")[0].permute(1, 2, 0)


def preview_sheet(path, avatar, body, size: int = 384) -> Path:
    """Write the preview sheet (module docstring) of a :class:`~relightnet.capture.CapturedAvatar` on ``body``."""
    from ..capture.body import CapturedBody
    from ..io import write_image

    views = turntable_views(CapturedBody(body, avatar), size)
    row = [_resize(avatar.texture, size), _confidence_image(avatar, size), *views]
    return write_image(Path(path), torch.cat(row, dim=1).clamp(0, 1))
