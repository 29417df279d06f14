"""The fit's camera: a pinhole at the origin looking along −z (relightnet's view space).

Intrinsics are ``(fx, fy, cx, cy)`` in continuous pixel coordinates
(:mod:`relightnet.raster.camera`): a view-space point (x, y, z), z < 0, lands at
``u = fx·x/(−z) + cx``, ``v = −fy·y/(−z) + cy``. The focal length comes from the photo's
EXIF (``FocalLengthIn35mmFilm``, scaled to the image's longer side as 36 mm) when it has one,
else from :data:`DEFAULT_FOV_DEG` across the longer side (a phone's main camera is about 65–70°).
"""

from __future__ import annotations

import math
from pathlib import Path

import torch

from ..checks import InputError, check_shape

__all__ = ["DEFAULT_FOV_DEG", "default_intrinsics", "exif_intrinsics", "project_points"]

#: Field of view (degrees) across the image's longer side when nothing better is known.
DEFAULT_FOV_DEG = 60.0


def default_intrinsics(size: tuple[int, int], fov_deg: float = DEFAULT_FOV_DEG) -> tuple[float, float, float, float]:
    """``(fx, fy, cx, cy)`` for an (H, W) image with ``fov_deg`` across its longer side."""
    h, w = int(size[0]), int(size[1])
    if not 0 < fov_deg < 180:
        raise InputError(f"fov_deg: expected a value in (0, 180), got {fov_deg}")
    f = (max(h, w) / 2) / math.tan(math.radians(fov_deg) / 2)
    return f, f, w / 2, h / 2


def exif_intrinsics(path: str | Path, size: tuple[int, int]) -> tuple[float, float, float, float] | None:
    """Intrinsics from a photo's EXIF 35 mm-equivalent focal length, or None when it has none."""
    try:
        from PIL import Image

        with Image.open(path) as im:
            exif = im.getexif()
            sub = exif.get_ifd(0x8769) if hasattr(exif, "get_ifd") else {}
            f35 = sub.get(0xA405) or exif.get(0xA405)
    except (OSError, ValueError, SyntaxError):
        return None
    try:
        f35 = float(f35)
    except (TypeError, ValueError):
        return None
    if not 5.0 <= f35 <= 1000.0:
        return None
    h, w = int(size[0]), int(size[1])
    f = f35 / 36.0 * max(h, w)
    return f, f, w / 2, h / 2


def project_points(points: torch.Tensor, intrinsics) -> torch.Tensor:
    """Project view-space points to pixels.

    Args:
        points: (..., 3) view-space points (in front of the camera: z < 0).
        intrinsics: ``(fx, fy, cx, cy)``.

    Returns:
        (..., 2) pixel coordinates (u, v).
    """
    check_shape(points, ["...", 3], name="points")
    fx, fy, cx, cy = (float(x) for x in intrinsics)
    depth = (-points[..., 2]).clamp_min(1e-3)
    return torch.stack([fx * points[..., 0] / depth + cx, -fy * points[..., 1] / depth + cy], dim=-1)
