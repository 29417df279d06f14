"""Morphology and local means on image masks (pure torch): the one erosion and dilation every part of
relightnet uses (the losses' inner mask, the Blender comparison's mask, the matte's border band) and the
one box filter (the guided filters of :mod:`relightnet.model.guided` and :mod:`relightnet.segment.matte`)."""

from __future__ import annotations

import torch
from torch.nn import functional as F

from ..checks import InputError, check_shape

__all__ = ["box_filter", "dilate", "erode"]


def erode(mask: torch.Tensor, radius: int = 2) -> torch.Tensor:
    """Binary erosion of (B, 1, H, W) masks by a (2r+1)² square (min-pooling); the image border
    does not erode. ``radius`` 0 returns the masks as they are.

    Args:
        mask: (B, 1, H, W) masks, values in [0, 1].
        radius: half the side of the square, in pixels (>= 0).

    Returns:
        (B, 1, H, W) eroded masks.

    Example:
        A 5 × 5 square loses its one-pixel rim:

        >>> import torch
        >>> from relightnet.raster import erode
        >>> mask = torch.zeros(1, 1, 9, 9)
        >>> mask[..., 2:7, 2:7] = 1
        >>> int(erode(mask, radius=1).sum()), int(erode(mask, radius=0).sum())
        (9, 25)
    """
    check_shape(mask, ("B", 1, "H", "W"), "mask")
    if radius < 0:
        raise InputError(f"radius: expected an integer >= 0, got {radius}")
    if radius == 0:
        return mask
    return -dilate(-mask, radius)


def dilate(mask: torch.Tensor, radius: int = 2) -> torch.Tensor:
    """Binary dilation of (B, 1, H, W) masks by a (2r+1)² square (max-pooling); the dual of :func:`erode`.

    Args:
        mask: (B, 1, H, W) masks, values in [0, 1].
        radius: half the side of the square, in pixels (>= 0).

    Returns:
        (B, 1, H, W) dilated masks.

    Example:
        >>> import torch
        >>> from relightnet.raster import dilate
        >>> mask = torch.zeros(1, 1, 9, 9)
        >>> mask[..., 4, 4] = 1
        >>> int(dilate(mask, radius=1).sum())
        9
    """
    check_shape(mask, ("B", 1, "H", "W"), "mask")
    if radius < 0:
        raise InputError(f"radius: expected an integer >= 0, got {radius}")
    if radius == 0:
        return mask
    k = 2 * radius + 1  # separable: a row max, then a column max (the same square, O(r) per pixel)
    rows = F.max_pool2d(mask, (1, k), stride=1, padding=(0, radius))
    return F.max_pool2d(rows, (k, 1), stride=1, padding=(radius, 0))


def box_filter(x: torch.Tensor, radius: int) -> torch.Tensor:
    """Mean over the (2r + 1)² window of each pixel, over the pixels that exist (border windows shrink).

    Args:
        x: (B, C, H, W).
        radius: r >= 0.

    Returns:
        (B, C, H, W).

    Example:
        >>> import torch
        >>> from relightnet.raster.morphology import box_filter
        >>> x = torch.zeros(1, 1, 3, 3)
        >>> x[..., 1, 1] = 9.0
        >>> box_filter(x, 1)[0, 0].tolist()  # corners average 4 pixels, edges 6, the centre 9
        [[2.25, 1.5, 2.25], [1.5, 1.0, 1.5], [2.25, 1.5, 2.25]]
    """
    if radius == 0:
        return x
    k = 2 * radius + 1  # separable: the shrinking window's count is a product of its row and column counts
    rows = F.avg_pool2d(x, (1, k), stride=1, padding=(0, radius), count_include_pad=False)
    return F.avg_pool2d(rows, (k, 1), stride=1, padding=(radius, 0), count_include_pad=False)
