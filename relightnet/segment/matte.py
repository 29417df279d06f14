"""A soft alpha matte in the person's border band, and the composite that uses it.

Away from the outline a person mask is right; its error is at the outline, where a binary mask
steps from pixel to pixel and a real edge covers a pixel in part. Only a narrow *band* around the
outline changes: the pixels within ``r`` of both a person and a background pixel (r =
:data:`BAND_FRACTION` of the image's shorter side, at least :data:`MIN_BAND` pixels).

The alpha in the band is a guided filter of the mask on the photo's colour (He, Sun & Tang,
"Guided Image Filtering", 2010): per window, the least-squares linear model q = a · I + b of the
mask p on the photo's three channels I, clamped to [0, 1]. On an edge between two flat colours
blended by a fractional coverage c the photo is linear in c, so q recovers c up to the
regularisation ``eps`` added to the colour covariance; a colour guide separates a person from a
background of the same brightness, which a luminance guide cannot. The coefficients are found at
1/s of the resolution (s ≈ r / 4, the "fast guided filter" of He & Sun, 2015) and interpolated at
the band's pixels only, so the cost follows the band, not the photo.

:func:`soft_composite` puts a relit person over the photo with that alpha, in linear light: a band
pixel's photo is α · F + (1 − α) · B (person F, background B, B carried in from the nearest pure
background pixels and F un-mixed from it); the relit pixel is α · G · F + (1 − α) · B, with G the
relighting's gain of the person (the pixel's own in the mask, the person's nearest pure pixels'
outside it). So the background behind a border pixel is never relit as the person, a person's edge
the mask missed is relit with the person, and outside the band nothing changes.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn
from torch.nn import functional as F

from ..checks import InputError, check_shape
from ..color import linear_to_srgb, srgb_to_linear
from ..raster.morphology import box_filter

__all__ = ["BAND_FRACTION", "MIN_BAND", "EdgeMatte", "band_radius", "border_band", "edge_matte",
           "soft_composite", "soft_matte", "SoftMatte"]

#: The band's half-width as a fraction of the image's shorter side.
BAND_FRACTION = 0.006
#: The band's smallest half-width, in pixels.
MIN_BAND = 2
#: Linear values below this are too dark to give a pixel's own gain.
_DARK = 1e-3
#: Rows converted to float at a time when a large photo is pooled (bounded temporaries).
_CHUNK = 512


def band_radius(h: int, w: int) -> int:
    """The border band's half-width in pixels for an (H, W) image (scaled with its size)."""
    return max(MIN_BAND, int(round(BAND_FRACTION * min(h, w))))


def _near(x: torch.Tensor, r: int) -> torch.Tensor:
    """(h, w) bool: a True of the (h, w) bool ``x`` within the (2r + 1)² square of each pixel (pixels
    past the border do not count), by running sums along rows then columns: O(1) per pixel."""
    for dim in (1, 0):
        n = x.shape[dim]
        c = F.pad(torch.cumsum(x, dim, dtype=torch.int32), (1, 0) if dim == 1 else (0, 0, 1, 0))
        i = torch.arange(n)
        x = (c.index_select(dim, (i + r + 1).clamp(max=n)) - c.index_select(dim, (i - r).clamp(min=0))) > 0
    return x


def _box_of(m: torch.Tensor, pad: int) -> tuple[int, int, int, int] | None:
    """``(y0, y1, x0, x1)``: the bounding box of the True pixels of (H, W) ``m`` grown by ``pad``, clipped."""
    rows, cols = torch.nonzero(m.any(1))[:, 0], torch.nonzero(m.any(0))[:, 0]
    if rows.numel() == 0:
        return None
    h, w = m.shape
    return (max(int(rows[0]) - pad, 0), min(int(rows[-1]) + 1 + pad, h),
            max(int(cols[0]) - pad, 0), min(int(cols[-1]) + 1 + pad, w))


def border_band(mask: torch.Tensor, radius: int) -> torch.Tensor:
    """(H, W) bool: the pixels within ``radius`` (a square's half-side) of both a person and a
    background pixel of a (H, W) mask thresholded at 0.5; pixels past the image's border count as neither."""
    check_shape(mask, ["H", "W"], name="mask")
    m = mask > 0.5
    band = torch.zeros_like(m)
    box = _box_of(m, radius + 1)  # the band lies within the person's box grown by the radius
    if box is not None and radius > 0:
        y0, y1, x0, x1 = box
        c = m[y0:y1, x0:x1]
        band[y0:y1, x0:x1] = _near(c, radius) & _near(~c, radius)
    return band


def _linear(x: torch.Tensor) -> torch.Tensor:
    """float32 linear RGB of sRGB ``x`` (uint8, or float in [0, 1])."""
    return srgb_to_linear(x.float() / 255 if x.dtype == torch.uint8 else x.float())


def _pool(x: torch.Tensor, s: int, weight: torch.Tensor | None = None) -> torch.Tensor:
    """(C, ⌈h/s⌉, ⌈w/s⌉) float: the means of (C, h, w) ``x`` (any dtype; uint8 read as /255) over
    s × s blocks (the last ones partial), times (h, w) ``weight`` first when given; in chunks of rows."""
    parts = []
    step = _CHUNK * s
    for r in range(0, x.shape[1], step):
        v = x[:, r:r + step]
        v = v.float() / 255 if v.dtype == torch.uint8 else v.float()
        if weight is not None:
            v = v * weight[r:r + step]
        parts.append(F.avg_pool2d(v[None], s, ceil_mode=True)[0] if s > 1 else v)
    return torch.cat(parts, 1)


def _sample(low: torch.Tensor, ys: torch.Tensor, xs: torch.Tensor, s: int) -> torch.Tensor:
    """(N, C): bilinear samples of the (C, h, w) block means ``low`` at full-resolution pixels (N,) ys, xs."""
    h, w = low.shape[1:]

    def axis(p, n):
        u = (p.float() + 0.5) / s - 0.5
        i0 = u.floor().clamp(0, n - 1).long()
        return i0, (i0 + 1).clamp(max=n - 1), (u - i0).clamp(0, 1)

    (y0, y1, fy), (x0, x1, fx) = axis(ys, h), axis(xs, w)
    fy, fx = fy[:, None], fx[:, None]
    top = low[:, y0, x0].T * (1 - fx) + low[:, y0, x1].T * fx
    bottom = low[:, y1, x0].T * (1 - fx) + low[:, y1, x1].T * fx
    return top * (1 - fy) + bottom * fy


def _fill(x: torch.Tensor, weight: torch.Tensor, ys, xs, s: int, reach: int) -> tuple[torch.Tensor, torch.Tensor]:
    """``(value (N, 3) linear, found (N,) bool)``: at pixels (ys, xs) the ``weight``-weighted mean of
    (3, h, w) sRGB ``x`` over about ``reach`` pixels (normalised convolution at 1/s resolution; the
    mean taken on the sRGB values, then decoded)."""
    num = box_filter(_pool(x, s, weight)[None], max(1, -(-reach // s)))[0]
    den = box_filter(_pool(weight[None].float(), s)[None], max(1, -(-reach // s)))[0]
    n, d = _sample(num, ys, xs, s), _sample(den, ys, xs, s)[:, 0]
    found = d > 1e-6
    return srgb_to_linear((n / d.clamp_min(1e-6)[:, None]).clamp(0, 1)), found


@dataclass(frozen=True, eq=False)
class EdgeMatte:
    """The person's soft edge in one photo: what :func:`soft_composite` needs (:func:`edge_matte`).
    Colours are linear RGB.

    Attributes:
        box: ``(y0, y1, x0, x1)`` the crop holding the band and the reach of its fills.
        ys, xs: (N,) long, the band's pixels (photo coordinates).
        alpha: (N,) float32 in [0, 1], their alpha.
        photo: (N, 3) the photo there.
        foreground: (N, 3) α · F, the person's share of the photo there (un-mixed from the background).
        person_fill: (N, 3) the photo's colour of the person's nearest pure pixels.
        person: (h, w) bool over ``box``: the person's pure pixels (in the mask, off the band), the
            sources of the gain carried into the band.
        own: (N, 3) bool, band pixels' channels in the mask, not dark: their own relit value gives their gain.
        scale: s, the fills' resolution divisor; ``reach``: their reach in pixels.
    """

    box: tuple[int, int, int, int]
    ys: torch.Tensor
    xs: torch.Tensor
    alpha: torch.Tensor
    photo: torch.Tensor
    foreground: torch.Tensor
    person_fill: torch.Tensor
    person: torch.Tensor
    own: torch.Tensor
    scale: int
    reach: int


def _guided(image, mask, ys, xs, r: int, s: int, eps: float) -> torch.Tensor:
    """(N,) the colour guided filter of ``mask`` on ``image`` (both over one crop) at (ys, xs): per
    window the mask's least-squares linear model a · I + b on the photo's three channels, the
    3 × 3 covariance regularised by eps (its inverse by the adjugate)."""
    # (1, 3, h/s, w/s) block means; float64: a two-colour edge makes the covariance nearly singular
    guide = _pool(image, s)[None].double()
    p = _pool(mask[None], s)[None].double()
    rl = max(1, round(r / s))
    mean_i, mean_p = box_filter(guide, rl), box_filter(p, rl)
    cov = box_filter(guide * p, rl) - mean_i * mean_p  # (1, 3, ·, ·)
    pairs = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]
    prod = torch.cat([guide[:, i:i + 1] * guide[:, j:j + 1] for i, j in pairs], 1)
    v = box_filter(prod, rl)[0] - torch.stack([mean_i[0, i] * mean_i[0, j] for i, j in pairs])
    xx, xy, xz, yy, yz, zz = v[0] + eps, v[1], v[2], v[3] + eps, v[4], v[5] + eps
    adj = torch.stack([yy * zz - yz * yz, xz * yz - xy * zz, xy * yz - xz * yy,
                       xx * zz - xz * xz, xy * xz - xx * yz, xx * yy - xy * xy])  # symmetric adjugate
    det = xx * adj[0] + xy * adj[1] + xz * adj[2]
    c = cov[0]
    a = torch.stack([adj[0] * c[0] + adj[1] * c[1] + adj[2] * c[2],
                     adj[1] * c[0] + adj[3] * c[1] + adj[4] * c[2],
                     adj[2] * c[0] + adj[4] * c[1] + adj[5] * c[2]]) / det
    coef = box_filter(torch.cat([a, mean_p[0] - (a * mean_i[0]).sum(0, keepdim=True)])[None], rl)[0]  # (4, ·, ·)
    ab = _sample(coef.float(), ys, xs, s)
    px = image[:, ys, xs]
    px = px.float() / 255 if px.dtype == torch.uint8 else px.float()
    return ((ab[:, :3] * px.T).sum(1) + ab[:, 3]).clamp_(0, 1)


def edge_matte(image: torch.Tensor, mask: torch.Tensor, radius: int | None = None,
               eps: float = 1e-4) -> EdgeMatte | None:
    """The soft edge of the person of a photo: the band, its alpha, and the person's and the
    background's shares of the photo there.

    Args:
        image: (3, H, W) the photo, sRGB in [0, 1] (or uint8).
        mask: (H, W) the segmentation's probability or a binary mask, in [0, 1].
        radius: the band's half-width and the filter's radius, in pixels (default :func:`band_radius`).
        eps: > 0, the guided filter's regularisation (added to the colour covariance, sRGB units squared).

    Returns:
        :class:`EdgeMatte`, or None when the mask has no outline (empty, or the whole photo).
    """
    d = check_shape(image, [3, "H", "W"], name="image")
    check_shape(mask, [d["H"], d["W"]], name="mask")
    if not eps > 0:
        raise InputError(f"matte eps: expected > 0, got {eps!r}")
    r = band_radius(d["H"], d["W"]) if radius is None else int(radius)
    if r < 1:
        raise InputError(f"matte radius: expected an integer >= 1, got {radius!r}")
    band = border_band(mask, r)
    box = _box_of(band, 3 * r)  # the filter reads 2r around a band pixel; the fills reach 2r past the band
    if box is None:
        return None
    y0, y1, x0, x1 = box
    img, m, b = image[:, y0:y1, x0:x1], mask[y0:y1, x0:x1], band[y0:y1, x0:x1]
    s = max(1, round(r / 4))
    ys, xs = torch.nonzero(b, as_tuple=True)
    alpha = _guided(img, m.float(), ys, xs, r, s, eps)
    photo = _linear(img[:, ys, xs].T)
    person, ground = (m > 0.5) & ~b, (m <= 0.5) & ~b
    bg, found = _fill(img, ground, ys, xs, s, 2 * r)
    bg = torch.where(found[:, None], bg, photo)  # no background within reach: the pixel's own colour
    fill, found = _fill(img, person, ys, xs, s, 2 * r)
    fill = torch.where(found[:, None], fill, photo)
    # α·F: un-mixed from the photo where the person covers most of the pixel, else the nearby person's colour
    a = alpha[:, None]
    unmixed = torch.minimum((photo - (1 - a) * bg).clamp_min(0), a)
    w = ((a - 0.25) / 0.5).clamp(0, 1)
    fg = torch.minimum(w * unmixed + (1 - w) * a * fill, photo)  # the person's share is at most the pixel
    own = (m[ys, xs] > 0.5)[:, None] & (photo > _DARK)
    return EdgeMatte(box, ys + y0, xs + x0, alpha, photo, fg, fill, person, own, s, 2 * r)


def soft_composite(out: torch.Tensor, matte: EdgeMatte | None) -> torch.Tensor:
    """Soften a binary composite's edge in place: in the band, photo + (G − 1) · α·F (linear light).

    G is the relighting's gain of the person there (the composite over the photo, per channel):
    a band pixel's own in the mask, the person's nearest pure pixels' outside it. The relit person's
    share of the pixel replaces its share of the photo and the background's share stays as shot:
    alpha 1 gives the relit pixel, alpha 0 the photo, and a light that changes nothing changes nothing.

    Args:
        out: (H, W, 3) the relit person over the photo composited with the binary mask, sRGB:
            float in [0, 1] or uint8 (rounded back).
        matte: the photo's :func:`edge_matte` (None: ``out`` is returned as it is).

    Returns:
        ``out``, changed in its band.
    """
    if matte is None:
        return out
    check_shape(out, ["H", "W", 3], name="composite")
    y0, y1, x0, x1 = matte.box
    crop = out[y0:y1, x0:x1].permute(2, 0, 1)
    relit = _linear(out[matte.ys, matte.xs])
    gain = relit / matte.photo.clamp_min(_DARK)
    near, found = _fill(crop, matte.person, matte.ys - y0, matte.xs - x0, matte.scale, matte.reach)
    near = torch.where(found[:, None], near / matte.person_fill.clamp_min(_DARK), torch.ones_like(near))
    gain = torch.where(matte.own, gain, near)
    v = linear_to_srgb((matte.photo + (gain - 1) * matte.foreground).clamp_(0, 1))
    out[matte.ys, matte.xs] = v.mul_(255).round_().to(out.dtype) if out.dtype == torch.uint8 else v.to(out.dtype)
    return out


def soft_matte(image: torch.Tensor, mask: torch.Tensor, radius: int | None = None,
               eps: float = 1e-4) -> torch.Tensor:
    """The person's alpha: ``mask > 0.5`` away from the outline, guided-filtered on the photo in the band.

    Args:
        image: (3, H, W) the photo, sRGB in [0, 1] (or uint8).
        mask: (H, W) the segmentation's probability or a binary mask, in [0, 1].
        radius: the band's half-width and the filter's radius, in pixels (default :func:`band_radius`).
        eps: > 0, the guided filter's regularisation (added to the colour covariance, sRGB units squared).

    Returns:
        (H, W) float32 alpha in [0, 1]; equal to ``mask > 0.5`` outside the band.
    """
    matte = edge_matte(image, mask, radius, eps)
    alpha = (mask > 0.5).float()
    if matte is not None:
        alpha[matte.ys, matte.xs] = matte.alpha
    return alpha


class SoftMatte(nn.Module):
    """:func:`soft_matte` with its radius and eps: ``forward(image (3, H, W), mask (H, W)) -> (H, W)``."""

    def __init__(self, radius: int | None = None, eps: float = 1e-4) -> None:
        super().__init__()
        self.radius, self.eps = radius, float(eps)

    def forward(self, image: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        return soft_matte(image, mask, self.radius, self.eps)
