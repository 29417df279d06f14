"""How good a capture is, measured against a generated clip's truth (:mod:`.truth`).

Textures are (S, S, 3) linear RGB in Anny's UV layout; a texel weight is (S, S), bool or
float (a float weight ≥ 0 weighs each texel's squared error). All results are Python floats.

- :func:`albedo_error`: relative RMSE after the one global scale that fits the texture to
  the truth best (least squares), ``sqrt(mean |s·x − y|²) / sqrt(mean |y|²)``: the sine of the
  angle between the two textures as vectors, so 0 for a texture right up to exposure and
  at most 1.
- :func:`light_invariance`: ``‖â − b̂‖ / ‖r̂_a − r̂_b‖``, the change of the captured albedo
  between two clips of one person under two lights, relative to the change of the raw
  (shaded) colours; every texture is first brought to unit RMS over the weighted texels, so
  a global exposure does not count. 0 for a capture that does not see the light, 1 for one
  that de-lights nothing.
- :func:`surface_texels` / :func:`seen_share`: the share of the body's visible surface that
  a capture saw: island texels only (not the padding around the UV islands), without the
  parts a camera never sees on a person (:data:`HIDDEN_PARTS`).
- :func:`silhouette_iou`: mean IoU of two mask sequences over the frames.
- :func:`person_psnr` / :func:`person_ssim`: image agreement over the person. The same
  measures for the CNN layout live in :mod:`relightnet.pipeline.metrics`, a higher floor
  this package may not import: these are the channels-last ones capture needs (the SSIM of
  Wang et al. 2004, an 11-tap Gaussian window of σ = 1.5, reflect padding, averaged over the
  mask; pixels outside the mask still enter the windows of the mask's edge).
"""

from __future__ import annotations

import math

import numpy as np
import torch
import torch.nn.functional as F

from ..checks import InputError, check_shape

__all__ = ["HIDDEN_PARTS", "albedo_error", "light_invariance", "surface_texels", "seen_share", "silhouette_iou",
           "person_psnr", "person_ssim"]

#: Anny parts no camera sees on a person (the back of the eyeballs, the eye sockets, the mouth's
#: inside): their texels do not count as surface. The eyes' fronts (the irises) do.
HIDDEN_PARTS = ("eye_back.L", "eye_back.R", "eye_cavity.L", "eye_cavity.R", "mouth_cavity", "tongue")

_F64 = torch.float64


def _tensor(x, name: str) -> torch.Tensor:
    if isinstance(x, np.ndarray):
        x = torch.from_numpy(np.ascontiguousarray(x))
    if not isinstance(x, torch.Tensor):
        raise InputError(f"{name}: expected a tensor or an array, got {type(x).__name__}")
    return x.detach().cpu()


def _textures(weight, **tex) -> tuple[list[torch.Tensor], torch.Tensor]:
    """Check (S, S, 3) textures and an (S, S) weight; return float64 textures and the (S·S,) float64 weight."""
    dims: dict = {}
    out = []
    for name, t in tex.items():
        t = _tensor(t, name)
        dims = check_shape(t, ["S", "S", 3], name=name, dims=dims)
        out.append(t.to(_F64).reshape(-1, 3))
    w = _tensor(weight, "weight")
    check_shape(w, ["S", "S"], name="weight", dims=dims)
    w = w.to(_F64).reshape(-1)
    if not bool(torch.isfinite(w).all()) or bool((w < 0).any()):
        raise InputError("weight: expected finite values >= 0")
    if not float(w.sum()) > 0:
        raise InputError("weight: no texel is weighted")
    if any(not bool(torch.isfinite(t[w > 0]).all()) for t in out):
        raise InputError(f"{', '.join(tex)}: expected finite values at the weighted texels")
    return out, w


def _sq(x: torch.Tensor, w: torch.Tensor) -> float:
    """Σ w |x|² of (N, 3) ``x``."""
    return float((w[:, None] * x * x).sum())


def albedo_error(tex, truth, weight) -> float:
    """Relative RMSE of a texture against the truth after one least-squares global scale.

    Args:
        tex: (S, S, 3) the captured albedo. truth: (S, S, 3) the true albedo.
        weight: (S, S) bool or float ≥ 0: the texels to count (e.g. those seen and on the surface).

    Returns:
        ``sqrt(Σ w |s·tex − truth|² / Σ w |truth|²)`` with ``s = Σ w tex·truth / Σ w |tex|²``
        (1 for a texture that is 0 at every weighted texel).

    Raises:
        ShapeError: shapes that do not match. InputError: no weighted texel, a true texture of 0 there.
    """
    (x, y), w = _textures(weight, tex=tex, truth=truth)
    yy = _sq(y, w)
    if not yy > 0:
        raise InputError("truth: zero at every weighted texel, the relative error is undefined")
    xx, xy = _sq(x, w), float((w[:, None] * x * y).sum())
    s = xy / xx if xx > 0 else 0.0
    return math.sqrt(max(_sq(s * x - y, w), 0.0) / yy)


def _unit(x: torch.Tensor, w: torch.Tensor, name: str) -> torch.Tensor:
    n = math.sqrt(_sq(x, w) / float(w.sum()))
    if not n > 0:
        raise InputError(f"{name}: zero at every weighted texel")
    return x / n


def light_invariance(tex_a, tex_b, raw_a, raw_b, weight) -> float:
    """How much the captured albedo follows the light, relative to the raw colours (module docstring).

    Args:
        tex_a, tex_b: (S, S, 3) albedo captured from the clips under lights a and b.
        raw_a, raw_b: (S, S, 3) the raw (shaded, not de-lit) colours of the same texels in each clip.
        weight: (S, S) bool or float ≥ 0: the texels both clips saw.

    Returns:
        ``‖â − b̂‖ / ‖r̂_a − r̂_b‖`` over the weighted texels, each texture scaled to unit RMS there.

    Raises:
        ShapeError: shapes that do not match. InputError: the raw textures agree up to a scale (no light change).
    """
    (a, b, ra, rb), w = _textures(weight, tex_a=tex_a, tex_b=tex_b, raw_a=raw_a, raw_b=raw_b)
    den = _sq(_unit(ra, w, "raw_a") - _unit(rb, w, "raw_b"), w)
    if not den > 1e-24 * float(w.sum()):
        raise InputError("raw_a, raw_b: equal up to a scale at the weighted texels, the light did not change them")
    return math.sqrt(_sq(_unit(a, w, "tex_a") - _unit(b, w, "tex_b"), w) / den)


def surface_texels(atlas) -> torch.Tensor:
    """(S, S) bool: the island texels of ``atlas`` (their ``texel_source`` is themselves) outside
    :data:`HIDDEN_PARTS` (the part of a texel's nearest vertex)."""
    from ..body.albedo import ANNY_PARTS

    S = atlas.size
    island = atlas.texel_source == np.arange(S * S)
    hidden = np.isin(atlas.parts[atlas.texel_vertex], [ANNY_PARTS.index(p) for p in HIDDEN_PARTS])
    return torch.from_numpy((island & ~hidden).reshape(S, S))


def seen_share(seen, atlas=None, body=None) -> float:
    """Share of the body's visible surface texels (:func:`surface_texels`) that were seen.

    Args:
        seen: (S, S) bool, the texels a capture saw (values > 0.5 for a float map).
        atlas: the body's :class:`~relightnet.data.textures.UVAtlas` of side S; None builds it
            from ``body`` (:func:`~relightnet.data.textures.uv_atlas`).
        body: :class:`~relightnet.body.AnnyBody`, read only when ``atlas`` is None.

    Returns:
        ``|seen ∩ surface| / |surface|`` in [0, 1].
    """
    seen = _tensor(seen, "seen")
    if atlas is None:
        if body is None:
            raise InputError("seen_share: give the atlas or the body")
        from ..data.textures import uv_atlas

        atlas = uv_atlas(body, seen.shape[-1])
    check_shape(seen, [atlas.size, atlas.size], name="seen")
    seen = seen if seen.dtype == torch.bool else seen > 0.5
    surf = surface_texels(atlas)
    return float((seen & surf).sum()) / max(int(surf.sum()), 1)


def silhouette_iou(a, b) -> float:
    """Mean IoU of two mask sequences over the frames whose union is not empty.

    Args:
        a, b: (…, H, W) masks of the same shape (bool, or values > 0.5 count); the leading axes are frames.

    Raises:
        ShapeError: the shapes differ or have fewer than 2 dims. InputError: every frame's union is empty.
    """
    a, b = _tensor(a, "a"), _tensor(b, "b")
    dims = check_shape(a, ["...", "H", "W"], name="a")
    check_shape(b, [*a.shape[:-2], "H", "W"], name="b", dims=dims)
    a = (a if a.dtype == torch.bool else a > 0.5).reshape(-1, *a.shape[-2:])
    b = (b if b.dtype == torch.bool else b > 0.5).reshape(-1, *b.shape[-2:])
    inter, union = (a & b).sum((1, 2)), (a | b).sum((1, 2))
    keep = union > 0
    if not bool(keep.any()):
        raise InputError("a, b: every frame's union is empty, the IoU is undefined")
    return float((inter[keep].to(_F64) / union[keep]).mean())


def _images(img, ref, mask) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """(…, H, W, C) pair and (…, H, W) mask → float64 (N, C, H, W) images and (N, 1, H, W) bool mask."""
    img, ref, mask = _tensor(img, "img"), _tensor(ref, "ref"), _tensor(mask, "mask")
    dims = check_shape(img, ["...", "H", "W", "C"], name="img")
    check_shape(ref, [*img.shape[:-3], "H", "W", "C"], name="ref", dims=dims)
    check_shape(mask, [*img.shape[:-3], "H", "W"], name="mask", dims=dims)
    m = (mask if mask.dtype == torch.bool else mask > 0.5).reshape(-1, 1, *mask.shape[-2:])
    if not bool(m.any()):
        raise InputError("mask: empty, no person to measure")
    x, y = (t.to(_F64).reshape(-1, *t.shape[-3:]).permute(0, 3, 1, 2) for t in (img, ref))
    return x, y, m


def person_psnr(img, ref, mask, data_range: float = 1.0) -> float:
    """PSNR over the person, in dB: ``10 log10(R² / MSE)`` over the masked pixels of every frame and the channels.

    Args:
        img, ref: (…, H, W, C) on a [0, ``data_range``] scale (e.g. sRGB in [0, 1]).
        mask: (…, H, W) the person (bool, or values > 0.5).

    Returns:
        The PSNR; ``inf`` for images that agree on the person.
    """
    if not data_range > 0:
        raise InputError(f"data_range: expected a positive number, got {data_range}")
    x, y, m = _images(img, ref, mask)
    mse = float((((x - y) ** 2) * m).sum()) / (float(m.sum()) * x.shape[1])
    return 10 * math.log10(data_range**2 / mse) if mse > 0 else math.inf


def person_ssim(img, ref, mask, data_range: float = 1.0) -> float:
    """Mean SSIM over the person (module docstring): the SSIM map averaged over the masked pixels and channels.

    Args:
        img, ref: (…, H, W, C) on a [0, ``data_range``] scale, H and W > 5.
        mask: (…, H, W) the person (bool, or values > 0.5).

    Returns:
        The mean SSIM (1 for images that agree).
    """
    if not data_range > 0:
        raise InputError(f"data_range: expected a positive number, got {data_range}")
    x, y, m = _images(img, ref, mask)
    if min(x.shape[-2:]) <= 5:
        raise InputError(f"img: SSIM needs H, W > 5, got {tuple(x.shape[-2:])}")
    g = torch.exp(-((torch.arange(11, dtype=_F64) - 5) ** 2) / (2 * 1.5**2))
    g = g / g.sum()
    n, c = x.shape[:2]

    def blur(t: torch.Tensor) -> torch.Tensor:  # (N, C', H, W) separable Gaussian, reflect padding
        k = t.shape[1]
        t = F.conv2d(F.pad(t, (5, 5, 0, 0), mode="reflect"), g.view(1, 1, 1, 11).expand(k, 1, 1, 11), groups=k)
        return F.conv2d(F.pad(t, (0, 0, 5, 5), mode="reflect"), g.view(1, 1, 11, 1).expand(k, 1, 11, 1), groups=k)

    mx, my, xx, yy, xy = blur(torch.cat([x, y, x * x, y * y, x * y], 1)).split(c, dim=1)
    c1, c2 = (0.01 * data_range) ** 2, (0.03 * data_range) ** 2
    vx, vy, cxy = xx - mx * mx, yy - my * my, xy - mx * my
    s = ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))
    return float((s * m).sum()) / (float(m.sum()) * c)
