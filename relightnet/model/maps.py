"""Maps in the CNN layout (channels first): shading T · L, relit A ⊙ (T · L), padding to the network's multiple.

The functions of :mod:`relightnet.render.shading` work on channels-last maps; the CNN's are
(B, C, H, W). These are the same kernels on channels-last views of the CNN's maps, used by the
network (:meth:`~relightnet.model.Prediction.shading`), its losses, evaluation and exposure rule, and
the jobs above.
"""

from __future__ import annotations

import torch
from torch.nn import functional as F

from ..checks import check_shape
from ..raster.interpolate import to_channels_first, to_channels_last
from ..render.shading import shade, shading

__all__ = ["shading_map", "shade_map", "relight", "pad_to_multiple"]


def shading_map(transport: torch.Tensor, light: torch.Tensor) -> torch.Tensor:
    """S = Σ_k T_k L_k in the CNN layout (:func:`relightnet.render.shading` on channels-last views).

    Args:
        transport: (B, K, H, W).
        light: (K, 3) or (B, K, 3).

    Returns:
        (B, 3, H, W).
    """
    dims = check_shape(transport, ["B", "K", "H", "W"], name="transport")
    check_shape(light, [dims["K"], 3] if light.dim() == 2 else [dims["B"], dims["K"], 3], name="light")
    return to_channels_first(shading(to_channels_last(transport), light))


def shade_map(albedo: torch.Tensor, transport: torch.Tensor, light: torch.Tensor) -> torch.Tensor:
    """A ⊙ (T · L) in the CNN layout (:func:`relightnet.render.shade` on channels-last views).

    Args:
        albedo: (B, 3, H, W) linear.
        transport: (B, K, H, W).
        light: (K, 3) or (B, K, 3).

    Returns:
        (B, 3, H, W) linear RGB.
    """
    dims = check_shape(transport, ["B", "K", "H", "W"], name="transport")
    check_shape(albedo, [dims["B"], 3, dims["H"], dims["W"]], name="albedo")
    return to_channels_first(shade(to_channels_last(albedo), to_channels_last(transport), light, check=False))


def relight(pred, new_light: torch.Tensor) -> torch.Tensor:
    """Relit image A ⊙ (T · L′) of a prediction's own maps (linear RGB, :func:`shade_map`).

    Args:
        pred: a :class:`~relightnet.model.Prediction` (its ``albedo`` and ``transport``).
        new_light: (K, 3) or (B, K, 3) light in the camera-relative light frame.

    Returns:
        (B, 3, H, W).
    """
    return shade_map(pred.albedo, pred.transport, new_light)


def pad_to_multiple(x: torch.Tensor, multiple: int = 16) -> tuple[torch.Tensor, tuple[int, int]]:
    """Zero-pad (B, C, H, W) at the bottom/right to multiples of ``multiple``; returns the original (H, W)."""
    h, w = x.shape[-2:]
    ph, pw = (-h) % multiple, (-w) % multiple
    return (F.pad(x, (0, pw, 0, ph)) if ph or pw else x), (h, w)
