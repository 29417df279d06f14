"""A soft alpha matte in the person's border band: the mask (or the segmentation's probability)
refined on the photo by a guided filter (He, Sun & Tang, "Guided Image Filtering", 2010).

Away from the outline a person mask is right; its error is at the outline, where a binary mask
steps from pixel to pixel and a real edge covers a pixel in part. :func:`soft_matte` changes only a
narrow *band* around the outline (the mask dilated minus the mask eroded, :data:`BAND_FRACTION` of
the image's shorter side, at least :data:`MIN_BAND` pixels): there the alpha is the local linear
model q = a · I + b of the input mask p on the photo's luminance I (box filters of ``radius``),
clamped to [0, 1]. On an edge between two flat colours blended by a fractional coverage c, the photo
is linear in c, so q recovers c up to the regularisation ``eps`` (the slope is shrunk by
var / (var + eps)). Only the band's bounding box (plus the filter's reach) is filtered.
"""

from __future__ import annotations

import torch
from torch import nn

from ..checks import InputError, check_shape
from ..raster.morphology import box_filter, dilate, erode

__all__ = ["BAND_FRACTION", "MIN_BAND", "band_radius", "border_band", "soft_matte", "SoftMatte"]

#: The band's half-width as a fraction of the image's shorter side.
BAND_FRACTION = 0.006
#: The band's smallest half-width, in pixels.
MIN_BAND = 2
#: Rec. 601 luma: the guide is the photo's luminance.
_LUMA = (0.299, 0.587, 0.114)


def band_radius(h: int, w: int) -> int:
    """The border band's half-width in pixels for an (H, W) image (scaled with its size)."""
    return max(MIN_BAND, int(round(BAND_FRACTION * min(h, w))))


def border_band(mask: torch.Tensor, radius: int) -> torch.Tensor:
    """(H, W) bool: the pixels within ``radius`` of the outline of a (H, W) mask (thresholded at 0.5)."""
    check_shape(mask, ["H", "W"], name="mask")
    m = (mask > 0.5).float()[None, None]
    return (dilate(m, radius) > erode(m, radius))[0, 0]


def soft_matte(image: torch.Tensor, mask: torch.Tensor, radius: int | None = None,
               eps: float = 1e-3) -> torch.Tensor:
    """The person's alpha: ``mask`` away from the outline, guided-filtered on the photo in the border band.

    Args:
        image: (3, H, W) the photo, sRGB in [0, 1] (or uint8).
        mask: (H, W) the segmentation's probability or a binary mask, in [0, 1].
        radius: the band's half-width and the box filters' radius, in pixels (default :func:`band_radius`).
        eps: > 0, the guided filter's regularisation (in squared luminance units).

    Returns:
        (H, W) float32 alpha in [0, 1]; equal to ``mask > 0.5`` outside the band.
    """
    d = check_shape(image, [3, "H", "W"], name="image")
    check_shape(mask, [d["H"], d["W"]], name="mask")
    if not eps > 0:
        raise InputError(f"matte eps: expected > 0, got {eps!r}")
    r = band_radius(d["H"], d["W"]) if radius is None else int(radius)
    if r < 1:
        raise InputError(f"matte radius: expected an integer >= 1, got {radius!r}")
    alpha = (mask > 0.5).float()
    band = border_band(mask, r)
    ys, xs = torch.nonzero(band, as_tuple=True)
    if ys.numel() == 0:
        return alpha
    # The band's box and the filters' reach (two box filters of radius r): nothing else is filtered.
    y0, y1 = max(int(ys.min()) - 2 * r, 0), min(int(ys.max()) + 1 + 2 * r, d["H"])
    x0, x1 = max(int(xs.min()) - 2 * r, 0), min(int(xs.max()) + 1 + 2 * r, d["W"])
    img = image[:, y0:y1, x0:x1]
    img = img.float() / 255 if img.dtype == torch.uint8 else img.float()
    guide = (torch.tensor(_LUMA).view(3, 1, 1) * img).sum(0)[None, None]
    p = mask[y0:y1, x0:x1].float()[None, None]
    mean_g, mean_p = box_filter(guide, r), box_filter(p, r)
    cov = box_filter(guide * p, r) - mean_g * mean_p
    var = (box_filter(guide * guide, r) - mean_g * mean_g).clamp_min(0)
    a = cov / (var + eps)
    b = mean_p - a * mean_g
    q = (box_filter(a, r) * guide + box_filter(b, r)).clamp_(0, 1)[0, 0]
    inner = band[y0:y1, x0:x1]
    alpha[y0:y1, x0:x1] = torch.where(inner, q, alpha[y0:y1, x0:x1])
    return alpha


class SoftMatte(nn.Module):
    """:func:`soft_matte` with its radius and eps: ``forward(image (3, H, W), mask (H, W)) -> (H, W)``."""

    def __init__(self, radius: int | None = None, eps: float = 1e-3) -> None:
        super().__init__()
        self.radius, self.eps = radius, float(eps)

    def forward(self, image: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        return soft_matte(image, mask, self.radius, self.eps)
