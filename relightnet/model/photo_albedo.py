"""The photo's own albedo: the photo divided by the predicted shading, its colour bounded where the shading is weak.

The CNN works at a small size (128² for the shipped model), so its albedo pasted back on a large
photo is blurred; dividing the photo by the (smooth) predicted shading S = T · L̂ keeps every detail
of the photo in the albedo, and relighting then changes the shading only, as with ratio images
(Wen, Liu & Huang, "Face relighting with radiance environment maps", CVPR 2003).

A per-channel division I_c / S_c also copies every error of the predicted shading's *colour* into
the albedo. Where the shading is weak (the far side of a dark coat, the edge of the hair, SH
ringing near a zero of T · L̂) its three channels are small numbers whose ratios are mostly error,
and a relit photo shows green and magenta blotches there. So the division is split into luminance
and chroma (Y = Rec. 709 luminance of linear RGB; S̄ the person's mean shading, Ȳ = Y(S̄), its tint
t = S̄ / Ȳ)::

    confidence   w_c = clamp((Y(S)/Ȳ − floor) / (CHROMA_FULL − floor), 0, 1)
    shading tint χ   = t · exp(w_c · clamp(log((S / Y(S)) / t), ±CHROMA_RANGE)),  then χ / Y(χ)
    divisor      D   = max(Y(S), floor · Ȳ) · χ
    albedo       A   = w · I / D + (1 − w) · Â,   w = clamp(Y(S) / (floor · Ȳ), 0, 1)

Where the shading is at least ``CHROMA_FULL`` of the person's mean and its colour within a factor
e^CHROMA_RANGE of the person's tint, D = S and A = I / S exactly (the per-channel ratio); where it
is weaker the divisor's colour slides to the person's mean tint, so the albedo keeps the photo's
own chromaticity divided by the light's overall colour — never a colour the shading invented. Below
``floor`` of the mean luminance there is nothing to divide the luminance by and the CNN's albedo Â
is blended in, recoloured with the photo's chromaticity over the tint (its own colour only where
the photo pixel is black, :data:`DARK`).
"""

from __future__ import annotations

import math

import torch

from ..checks import check_shape
from ..color import LUMA

__all__ = ["ALBEDO_FLOOR", "CHROMA_FULL", "CHROMA_RANGE", "ROW_BAND", "photo_albedo", "photo_albedo_rows",
           "person_mean_shading"]

#: Below this fraction of the person's mean shading luminance the photo albedo takes the CNN's.
ALBEDO_FLOOR = 0.05
#: From this fraction of the person's mean shading luminance up, the shading's own colour divides the photo.
CHROMA_FULL = 0.5
#: The most (natural log) the divisor's colour may differ from the person's mean shading tint, per channel.
CHROMA_RANGE = math.log(2.0)
#: Linear luminance below which a photo pixel's colour is mostly noise (8-bit sRGB 1/255 is 3e-4 linear).
DARK = 1e-3
#: Rows per band for full-resolution passes (the temporaries of a large photo stay small).
ROW_BAND = 256


def _luma(x: torch.Tensor) -> torch.Tensor:
    """(B, 3, ...) → (B, 1, ...) Rec. 709 luminance (channel dimension 1)."""
    w = torch.tensor(LUMA, dtype=x.dtype, device=x.device).view(1, 3, *([1] * (x.dim() - 2)))
    return (x * w).sum(1, keepdim=True)


def person_mean_shading(shading: torch.Tensor, mask: torch.Tensor | None) -> torch.Tensor:
    """(B, 3, 1, 1) the mean of the shading (B, 3, H, W) over the person (mask (B, 1, H, W); None: all pixels)."""
    m = torch.ones_like(shading[:, :1]) if mask is None else mask.to(shading)
    return (shading * m).sum((2, 3), keepdim=True) / m.sum((2, 3), keepdim=True).clamp_min(1e-8)


def photo_albedo_rows(image: torch.Tensor, shading: torch.Tensor, albedo: torch.Tensor, mean: torch.Tensor,
                      floor: float = ALBEDO_FLOOR) -> torch.Tensor:
    """The photo albedo (module docstring) of some rows, given the person's mean shading over the whole photo.

    Args:
        image: (B, 3, H, W) the photo, linear RGB.
        shading: (B, 3, H, W) the predicted shading T · L̂ of the same pixels.
        albedo: (B, 3, H, W) the CNN's albedo (taken where the shading is below ``floor``).
        mean: (B, 3, 1, 1) the person's mean shading (:func:`person_mean_shading` of the whole photo).
        floor: fraction of the mean shading luminance below which the CNN's albedo takes over.

    Returns:
        (B, 3, H, W) albedo, non-negative (above 1 where the photo has highlights).
    """
    mean = mean.to(shading)
    y_mean = _luma(mean).clamp_min(1e-6)
    tint = (mean / y_mean).clamp_min(1e-3)
    tint = tint / _luma(tint)
    tau = floor * y_mean
    y = _luma(shading)
    y_div = torch.maximum(y, tau)
    local = (shading / y_div).clamp_min(1e-3 * tint)
    w_c = ((y / y_mean - floor) / (CHROMA_FULL - floor)).clamp(0, 1)
    chroma = tint * torch.exp(w_c * torch.log(local / tint).clamp(-CHROMA_RANGE, CHROMA_RANGE))
    divisor = y_div * chroma / _luma(chroma)
    w = (y / tau).clamp(0, 1)
    photo = image.to(shading).clamp_min(0)
    return (w * photo / divisor + (1 - w) * _recoloured(albedo, photo / tint)).clamp_min(0)


def _recoloured(albedo: torch.Tensor, colour: torch.Tensor) -> torch.Tensor:
    """The CNN's albedo luminance with the colour of ``colour`` (the photo over the light's tint, (B, 3, H, W)),
    sliding to the CNN's own colour where the photo is too dark to have one (below ~:data:`DARK` linear)."""
    y_a = _luma(albedo)
    mix = colour + DARK * albedo / y_a.clamp_min(1e-6)
    return y_a * mix / _luma(mix).clamp_min(1e-12)


def photo_albedo(image: torch.Tensor, pred, floor: float = ALBEDO_FLOOR,
                 shading: torch.Tensor | None = None) -> torch.Tensor:
    """Albedo at the photo's own resolution: the photo divided by the predicted shading (module docstring).

    Args:
        image: (B, 3, H, W) the photo, *linear* RGB, at the prediction's size.
        pred: :class:`~relightnet.model.Prediction` at the same size (its mask, when present, sets the mean).
        floor: fraction of the mean shading luminance below which the CNN's albedo takes over.
        shading: ``pred.shading()`` when the caller has it already, (B, 3, H, W).

    Returns:
        (B, 3, H, W) albedo (non-negative; above 1 where the photo has highlights).
    """
    dims = check_shape(image, ["B", 3, "H", "W"], name="image")
    check_shape(pred.albedo, [dims["B"], 3, dims["H"], dims["W"]], name="prediction albedo")
    if shading is None:
        shading = pred.shading()
    check_shape(shading, [dims["B"], 3, dims["H"], dims["W"]], name="shading")
    mean = person_mean_shading(shading, pred.mask)
    if torch.is_grad_enabled() and (shading.requires_grad or pred.albedo.requires_grad):
        return photo_albedo_rows(image, shading, pred.albedo, mean, floor)
    out = torch.empty_like(shading)  # in bands of rows: a large photo's temporaries stay small (same values)
    for r in range(0, dims["H"], ROW_BAND):
        band = slice(r, r + ROW_BAND)
        out[:, :, band] = photo_albedo_rows(image[:, :, band], shading[:, :, band], pred.albedo[:, :, band], mean,
                                            floor)
    return out
