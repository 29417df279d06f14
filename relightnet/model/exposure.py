"""Keeping a photo's exposure when it is relit: the new light scaled to the person's old shading level.

Lights come at any scale (a projected HDRI's sun reaches 1e4). Relighting keeps the person as bright
as in the photo while the direction and colour of the light change: the new light is scaled so that
the mean shading luminance over the person's mask, T · L′, equals that of the photo's own light.
``relight-image``, ``relight-video`` and ``compare`` match one level over a whole batch of frames
(the frames of a clip keep their relative brightness); the round trip of training
(:func:`relightnet.model.round_trip.relit_input`) matches each item on its own.

- :func:`exposure_level`: the mean shading luminance over a mask (pooled, or per item);
- :func:`transport_level`: the same level in closed form from the mask-weighted transport (shading is
  linear in the light: a level under any light costs one (K,) · (K, 3) product);
- :func:`exposure_scale`: the factor between two levels, 1 where there is nothing to match;
- :func:`match_exposure`: a new light scaled to a prediction's own level.
"""

from __future__ import annotations

import torch

from ..checks import check_shape
from ..color import LUMA, luminance
from ..raster.interpolate import to_channels_last
from .maps import shading_map
from .network import Prediction

__all__ = ["exposure_level", "transport_level", "exposure_scale", "match_exposure"]


def exposure_level(shading: torch.Tensor, mask: torch.Tensor, per_item: bool = False) -> torch.Tensor:
    """Mean Rec. 709 luminance of ``shading`` over ``mask``.

    Args:
        shading: (B, 3, H, W) linear shading T · L.
        mask: (B, 1, H, W) the person's coverage in [0, 1].
        per_item: one level per item instead of one over the batch.

    Returns:
        () or (B,) with ``per_item``, the dtype of ``shading`` (0 where the mask is empty).
    """
    dims = check_shape(shading, ["B", 3, "H", "W"], name="shading")
    check_shape(mask, [dims["B"], 1, dims["H"], dims["W"]], name="mask")
    lum = luminance(to_channels_last(shading))[:, None] * mask
    if per_item:
        return lum.sum((1, 2, 3)) / mask.sum((1, 2, 3)).clamp_min(1)
    return lum.sum() / mask.sum().clamp_min(1)


def transport_level(transport_sum: torch.Tensor, light: torch.Tensor, mass: float = 1.0) -> float:
    """:func:`exposure_level` of one photo in closed form: ``luminance(Σ T · L) / mass``, in float64.

    Args:
        transport_sum: (K,) the transport summed over the person, each pixel weighted by its mask
            (or already divided by the mask's sum, with ``mass`` 1).
        light: (K, 3) the light.
        mass: the mask's sum (floored at 1, as :func:`exposure_level` does).

    Returns:
        The mean shading luminance over the mask under ``light``.
    """
    luma = torch.tensor(LUMA, dtype=torch.float64)
    return float(transport_sum.double() @ light.double() @ luma) / max(mass, 1.0)


def exposure_scale(old: torch.Tensor | float, new: torch.Tensor | float) -> torch.Tensor:
    """The factor ``old / new`` that brings shading level ``new`` to ``old``, in float64.

    Args:
        old, new: levels of the same shape (any; floats become 0-dim tensors).

    Returns:
        float64 of that shape: 1 where ``new`` ≤ 1e-8 (a light that does not reach the person) or
        ``old`` ≤ 0 (no exposure to keep).
    """
    old = torch.as_tensor(old, dtype=torch.float64)
    new = torch.as_tensor(new, dtype=torch.float64)
    return torch.where((new > 1e-8) & (old > 0), old / new.clamp_min(1e-8), torch.ones_like(new))


def match_exposure(new_light: torch.Tensor, pred: Prediction, shading: torch.Tensor | None = None,
                   per_item: bool = False) -> torch.Tensor:
    """``new_light`` scaled so the person's mean shading luminance stays what it was under ``pred.light``.

    Args:
        new_light: (K, 3) or (B, K, 3) light at the prediction's order.
        pred: the :class:`Prediction` of the photo (its mask sets where the level is taken; none: everywhere).
        shading: ``pred.shading()`` (B, 3, H, W) when the caller has it already.
        per_item: scale each item's light to its own level (then (B, K, 3) out) instead of one
            factor for the batch.

    Returns:
        ``new_light`` scaled: its shape and dtype, or (B, K, 3) with ``per_item``.
    """
    old_shading = pred.shading() if shading is None else shading
    mask = pred.mask if pred.mask is not None else torch.ones_like(old_shading[:, :1])
    old = exposure_level(old_shading, mask, per_item)
    new = exposure_level(shading_map(pred.transport, new_light.to(pred.transport)), mask, per_item)
    scale = exposure_scale(old, new)
    return new_light * (scale.to(new_light.dtype)[:, None, None] if per_item else scale)
