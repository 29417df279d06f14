"""The CNN at a lower resolution: its input pooled, its maps brought back by a trainable fast guided filter.

Shading is smooth except at occlusion edges, and :func:`~relightnet.model.photo_albedo.photo_albedo` takes
the albedo's detail from the photo, so a network can predict its maps at half the resolution
(``NetConfig.work_scale``). :func:`pool_input` halves the normalised (KE18) input;
:func:`fast_guided_upsample` brings each low-resolution map back to full resolution along the
edges of a full-resolution guide (He & Sun, "Fast Guided Filter", 2015; Wu et al., "Fast
End-to-End Trainable Guided Filter", CVPR 2018): per low-resolution pixel the local linear model
p ≈ A · g between the pooled guide g and the map p (box filters of ``radius``), A bilinearly upsampled
and applied to the full-resolution guide G.

One departure from the papers: the offset is b = p − Ā · g at each low-resolution pixel (Ā the
box-averaged slope), not the box average of b. So the filter interpolates the map, never blurs
it: with a constant guide it *is* bilinear upsampling, and elsewhere it adds to the bilinear
upsampling of p the guide's detail lost in pooling, Ā · (G − upsampled g) where Ā is constant.
"""

from __future__ import annotations

import math

import torch
from torch import nn
from torch.nn import functional as F

from ..checks import InputError, ShapeError
from ..raster.morphology import box_filter

__all__ = ["fast_guided_upsample", "FastGuidedUpsample", "pool_input", "double_to", "LUMA"]

#: Rec. 601 luma weights: the guide's starting point (the person's luminance).
LUMA = (0.299, 0.587, 0.114)


def fast_guided_upsample(low: torch.Tensor, guide: torch.Tensor, scale: int, radius: int = 1,
                         eps: float | torch.Tensor = 1e-2) -> torch.Tensor:
    """Upsample ``low`` by ``scale`` along the edges of ``guide`` (module docstring).

    Computed in float32 (float64 stays float64): with g the guide average-pooled by ``scale`` and
    box() the mean over a (2r + 1)² window, A = cov(g, p) / (var(g) + eps), Ā = box(A),
    b = p − Ā · g; the result is up(Ā) · G + up(b) with up() bilinear (half-pixel centres).
    A map that is a linear function a · g + c of the guide comes back as a · G + c (eps → 0); with a
    constant guide the result is the bilinear upsampling of ``low``.

    Args:
        low: (B, C, h, w) the low-resolution map.
        guide: (B, C, H, W) or (B, 1, H, W) the full-resolution guide, H = scale · h, W = scale · w.
        scale: integer factor >= 1.
        radius: r of the box filters, in low-resolution pixels.
        eps: > 0, a float or a (C,) tensor (one per channel): the regularisation of the slope A.

    Returns:
        (B, C, H, W) in ``low``'s float dtype (float32 or float64).
    """
    if low.dim() != 4 or guide.dim() != 4:
        raise ShapeError(f"guided upsample: expected low (B, C, h, w) and guide (B, C, H, W), "
                         f"got {tuple(low.shape)} and {tuple(guide.shape)}")
    if isinstance(scale, bool) or not isinstance(scale, int) or scale < 1:
        raise InputError(f"guided upsample scale: expected an integer >= 1, got {scale!r}")
    b, c, h, w = low.shape
    if guide.shape[0] != b or guide.shape[1] not in (1, c) or guide.shape[2] != h * scale \
            or guide.shape[3] != w * scale:
        raise ShapeError(f"guided upsample guide: expected ({b}, {c} or 1, {h * scale}, {w * scale}) for low "
                         f"{tuple(low.shape)} at scale {scale}, got {tuple(guide.shape)}")
    if isinstance(eps, float | int) and not eps > 0:
        raise InputError(f"guided upsample eps: expected > 0, got {eps!r}")
    dtype = torch.float64 if low.dtype == torch.float64 else torch.float32
    p, big = low.to(dtype), guide.to(dtype)
    if isinstance(eps, torch.Tensor):
        eps = eps.to(dtype).reshape(1, -1, 1, 1)
    g = F.avg_pool2d(big, scale) if scale > 1 else big
    mean_g, mean_p = box_filter(g, radius), box_filter(p, radius)
    cov = box_filter(g * p, radius) - mean_g * mean_p
    var = (box_filter(g * g, radius) - mean_g * mean_g).clamp_min(0)
    slope = box_filter(cov / (var + eps), radius)
    offset = p - slope * g
    if scale == 1:
        return slope * big + offset
    up = [F.interpolate(t, scale_factor=float(scale), mode="bilinear", align_corners=False) for t in (slope, offset)]
    return up[0] * big + up[1]


class FastGuidedUpsample(nn.Module):
    """:func:`fast_guided_upsample` with a learned guide and a learned eps per channel.

    The guide is a 1×1 convolution of the full-resolution network input (the KE18 input of
    :func:`~relightnet.model.network.normalize_input`, 4 channels), one guide channel per map channel,
    starting as the person's luminance on black (Rec. 601 of (x + mask) / 2); eps starts at ``eps``.

    ``forward(low, x)``: low (B, C, h, w), x (B, 4, H, W) with H = scale · h -> (B, C, H, W) float32.
    """

    def __init__(self, channels: int, scale: int = 2, radius: int = 1, eps: float = 1e-2) -> None:
        super().__init__()
        self.scale, self.radius = int(scale), int(radius)
        self.guide = nn.Conv2d(4, channels, 1)
        with torch.no_grad():
            self.guide.weight.zero_()
            self.guide.weight[:, :3, 0, 0] = torch.tensor(LUMA) / 2
            self.guide.weight[:, 3, 0, 0] = sum(LUMA) / 2
            self.guide.bias.zero_()
        self.log_eps = nn.Parameter(torch.full((channels,), math.log(eps)))

    def forward(self, low: torch.Tensor, x: torch.Tensor) -> torch.Tensor:
        return fast_guided_upsample(low, self.guide(x.to(self.guide.weight.dtype)), self.scale, self.radius,
                                    self.log_eps.exp())


def pool_input(x: torch.Tensor, scale: int) -> torch.Tensor:
    """The network input at 1/``scale``: average pooling of each channel.

    Pooling the KE18 input ((2·image − 1) · mask, mask) is again a KE18 input: of the pooled (soft)
    mask and of the mask-weighted mean colour of each block, mean(image · mask) / mean(mask).
    A CNN of ``levels`` stride-2 levels runs on sides that are not multiples of 2**levels (its
    deepest maps round up; the pose network's taps round up alike).

    Args:
        x: (B, 4, H, W) from :func:`~relightnet.model.network.normalize_input`, H and W multiples of ``scale``.
        scale: integer factor >= 1.

    Returns:
        (B, 4, H / scale, W / scale).
    """
    if x.dim() != 4 or x.shape[1] != 4:
        raise ShapeError(f"input: expected (B, 4, H, W) from normalize_input, got {tuple(x.shape)}")
    if x.shape[-2] % scale or x.shape[-1] % scale:
        raise ShapeError(f"input: H and W must be multiples of {scale}, got {tuple(x.shape[-2:])}")
    return F.avg_pool2d(x, scale) if scale > 1 else x


def double_to(x: torch.Tensor, skip: torch.Tensor) -> torch.Tensor:
    """Bilinear ×2 upsampling of ``x``, cropped to ``skip``'s size where that is odd (the decoder of a network at
    half resolution: its ONNX Resize then has constant scales; resizing to the skip's size, as the
    full-resolution network does, gives sizes that ONNX shape inference cannot follow).

    Args:
        x: (B, C, h, w).
        skip: (B, C′, H, W) with H in (2h − 1, 2h) and W in (2w − 1, 2w).

    Returns:
        (B, C, H, W).
    """
    x = F.interpolate(x, scale_factor=2.0, mode="bilinear", align_corners=False)
    if x.shape[-2:] != skip.shape[-2:]:
        x = x[..., : skip.shape[-2], : skip.shape[-1]]
    return x
