"""Binary morphology on image masks (pure torch): the one erosion every part of relightnet uses
(the losses' inner mask, the Blender comparison's mask)."""

from __future__ import annotations

import torch
from torch.nn import functional as F

from ..checks import InputError, check_shape

__all__ = ["erode"]


def erode(mask: torch.Tensor, radius: int = 2) -> torch.Tensor:
    """Binary erosion of (B, 1, H, W) masks by a (2r+1)² square (min-pooling); the image border
    does not erode. ``radius`` 0 returns the masks as they are.

    Args:
        mask: (B, 1, H, W) masks, values in [0, 1].
        radius: half the side of the square, in pixels (>= 0).

    Returns:
        (B, 1, H, W) eroded masks.
    """
    check_shape(mask, ("B", 1, "H", "W"), "mask")
    if radius < 0:
        raise InputError(f"radius: expected an integer >= 0, got {radius}")
    if radius == 0:
        return mask
    return -F.max_pool2d(-mask, 2 * radius + 1, stride=1, padding=radius)
