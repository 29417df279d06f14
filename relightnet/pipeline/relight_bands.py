"""Relighting a photo or a video frame at its full resolution in bands of rows (bounded memory).

The CNN's maps are predicted at its working size; a large photo needs them at its own size,
where a 12.5 MP frame's albedo and K = 9 transport alone take 600 MB. :func:`relight_over_photo`
never holds them whole: the maps of a band of :data:`~relightnet.model.photo_albedo.ROW_BAND` rows are
pasted (:meth:`~relightnet.model.inference.CropMaps.rows`), relit and composited over the photo,
and the band's result is written into the output before the next band is pasted. Only the rows and
columns the person's mask spans are computed (:meth:`~relightnet.model.inference.CropMaps.span`):
every other pixel is the photo's. The two numbers
the whole person decides (the exposure of the light and the person's mean shading, which bounds the photo albedo)
come from a first pass that sums the person's transport, Σ m·T_k: the mean shading under any
light L is that sum times L (shading is linear in the light), so both are found without a full
shading map. The result equals the whole-photo formulas on the pasted prediction
(:meth:`~relightnet.model.inference.CropMaps.pasted`, :func:`~relightnet.model.photo_albedo`,
:func:`relightnet.render.shade`, :func:`relightnet.render.composite`) to float32 rounding; peak memory
is the photo, its mask, the output and one band's maps.

:func:`relight_over_photo` is the one photo relight of the package: ``relight-image`` (through
:func:`~relightnet.pipeline.relight_image.relight_image`), ``relight-video``, ``evaluate --photos``,
the 2D path of ``compare`` (``composite=False``: the relit person in linear RGB) and the demo call it;
:class:`RelitPhoto` is what it returns.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from ..checks import InputError, check_finite, check_shape
from ..color import linear_to_srgb, luminance, srgb_to_linear
from ..model.exposure import exposure_scale, transport_level
from ..model.inference import CropMaps
from ..model.maps import shading_map
from ..model.network import Prediction
from ..model.photo_albedo import ROW_BAND, photo_albedo_rows
from ..raster.interpolate import to_channels_last
from ..render.shading import composite, shade
from ..segment.matte import edge_matte, soft_composite

__all__ = ["RelitPhoto", "is_gray", "relight_over_photo", "transport_sum"]


@dataclass(frozen=True, eq=False)
class RelitPhoto:
    """A relit photo: what :func:`relight_over_photo` and :func:`~relightnet.pipeline.relight_image` return.

    Attributes:
        image: (H, W, 3) the relit person over the photo, sRGB: float in [0, 1] or uint8; with
            ``composite=False`` the relit person alone, linear RGB (float, unclamped), zero off the person.
        light: (K, 3) the light used (exposure-matched when asked).
        lit: the fraction of the person (by mask) whose shading under ``light`` is positive.
        albedo: (3, H, W) the albedo that was relit (linear), when asked; else None.
        prediction: the CNN's :class:`~relightnet.model.Prediction` at the photo's resolution (batch 1),
            when :func:`~relightnet.pipeline.relight_image` was asked for maps; else None.
        mask_predicted: whether the person's mask came from the model's mask head.
    """

    image: torch.Tensor
    light: torch.Tensor
    lit: float
    albedo: torch.Tensor | None = None
    prediction: Prediction | None = None
    mask_predicted: bool = False


def transport_sum(maps: CropMaps, span: tuple[int, int, int, int] | None = None) -> tuple[torch.Tensor, float]:
    """``(Σ m·T_k (K,) float64, Σ m)`` over the photo: the person's transport weighted by its mask
    (T is already zero outside it), summed one band of rows at a time over the mask's span
    (``span``: :meth:`CropMaps.span <relightnet.model.inference.CropMaps.span>`, found here when None)."""
    total = torch.zeros(maps.transport.shape[1], dtype=torch.float64)
    mass = 0.0
    span = maps.span() if span is None else span
    if span is None:
        return total, mass
    r0, r1, c0, c1 = span
    for r in range(r0, r1, ROW_BAND):
        _, t, m = maps.rows(r, min(r + ROW_BAND, r1), albedo=False, cols=(c0, c1))
        total += (t * m).sum((0, 2, 3), dtype=torch.float64)
        mass += float(m.sum(dtype=torch.float64))
    return total, mass


def _photo_as(image: torch.Tensor, dtype: torch.dtype) -> torch.Tensor:
    """(3, H, W) photo (sRGB, float or uint8) -> (H, W, 3) of ``dtype``: what every pixel outside the
    person is in the output (float in [0, 1] as given; uint8 rounded, as the bands round theirs)."""
    x = image.permute(1, 2, 0)  # a new tensor in each case: the output never shares the photo's memory
    if dtype == torch.uint8:
        return x.clone(memory_format=torch.contiguous_format) if x.dtype == torch.uint8 \
            else x.float().clamp(0, 1).mul(255).round().to(torch.uint8)
    return x.float().div(255) if x.dtype == torch.uint8 else x.to(dtype).clone(memory_format=torch.contiguous_format)


def is_gray(image: torch.Tensor) -> bool:
    """True when a photo has no colour: its three channels equal to within one 8-bit level.

    Args:
        image: (3, H, W) sRGB in [0, 1] or uint8.
    """
    check_shape(image, [3, "H", "W"], name="image")
    tol = 1 if image.dtype == torch.uint8 else 1.0 / 255 + 1e-6
    lo, hi = image.aminmax(dim=0)
    return bool(((hi.float() - lo.float()) <= tol).all())


@torch.no_grad()
def relight_over_photo(maps: CropMaps, image: torch.Tensor, light: torch.Tensor, detail: bool = True,
                       keep_exposure: bool = True, reference: torch.Tensor | None = None,
                       dtype: torch.dtype = torch.float32, keep_albedo: bool = False,
                       soft_edges: bool = False, composite: bool = True) -> RelitPhoto:
    """Relight the person of a photo with a new light and put them over the photo, band by band.

    Args:
        maps: the CNN's prediction for the photo (:meth:`Predictor.crop <relightnet.pipeline.backends.Predictor>`).
        image: (3, H, W) the photo, sRGB in [0, 1] (or uint8).
        light: (K, 3) new light at the model's order, camera-relative light frame.
        detail: relight the photo's own albedo (photo / predicted shading,
            :func:`~relightnet.model.photo_albedo`); False relights the CNN's albedo.
        keep_exposure: scale the light so the person keeps the photo's exposure
            (:func:`~relightnet.model.exposure.match_exposure`'s
            level, here from :func:`transport_sum`).
        reference: (K, 3) the light taken as the photo's own (exposure reference, divisor of the
            photo albedo); default the predicted light (a video passes its smoothed estimate).
        dtype: ``torch.float32`` (values in [0, 1]) or ``torch.uint8`` (rounded, what a video frame is).
        keep_albedo: also return the relit albedo (3, H, W) (``--save-maps``; a photo's worth of memory).
        soft_edges: composite the person's border band with a soft matte
            (:func:`~relightnet.segment.matte.soft_composite`: the alpha refined on the photo, the relit
            colour there from the person's side); False pastes with the mask as it is.
        composite: False returns the relit person alone, A ⊙ (T · L′) in linear RGB (H, W, 3) float32,
            unclamped and zero off the person (the 2D path of ``compare``; ``dtype`` and ``soft_edges``
            must then be left as they are).

    A photo without colour (:func:`is_gray`) gives a person without colour: the relit person's
    luminance, whatever the light's colour.

    Returns:
        :class:`RelitPhoto`.
    """
    h, w = maps.size
    check_shape(image, [3, h, w], name="image")
    check_finite(light, "light")
    if not composite and (dtype != torch.float32 or soft_edges):
        raise InputError("composite=False: the relit person is linear float32 without a soft edge; "
                         "expected dtype=torch.float32 and soft_edges=False")
    ref = (maps.light[0] if reference is None else reference).to(maps.transport)
    span = maps.span()
    total, mass = transport_sum(maps, span)
    new = light.to(maps.transport)
    if keep_exposure:
        new = new * exposure_scale(transport_level(total, ref, mass), transport_level(total, new, mass))
    mean = ((total @ ref.double()) / max(mass, 1e-8)).to(new).view(1, 3, 1, 1)  # the person's mean shading
    # the person's span is relit below; the rest stays the photo (or zero: the person alone)
    out = _photo_as(image, dtype) if composite else torch.zeros(h, w, 3)
    albedo_out = torch.zeros(3, h, w) if keep_albedo else None
    lit, gray = 0.0, is_gray(image)
    r0, r1, c0, c1 = span or (0, 0, 0, 0)
    for r in range(r0, r1, ROW_BAND):
        rb = min(r + ROW_BAND, r1)
        a, t, m = maps.rows(r, rb, cols=(c0, c1))
        photo = image[None, :, r:rb, c0:c1]
        photo = photo.float() / 255 if photo.dtype == torch.uint8 else photo.to(t)
        if detail:
            a = photo_albedo_rows(srgb_to_linear(photo), shading_map(t, ref), a, mean)
        linear, shading = shade(to_channels_last(a), to_channels_last(t), new, check=False, with_shading=True)
        lit += float(((shading.mean(-1) > 0) * m[:, 0]).sum(dtype=torch.float64))
        if gray:
            linear = luminance(linear)[..., None].expand_as(linear)
        out[r:rb, c0:c1] = _over_photo(linear, m, photo, dtype)[0] if composite else linear[0]
        if albedo_out is not None:
            albedo_out[:, r:rb, c0:c1] = a[0]
    if soft_edges:
        soft_composite(out, edge_matte(image, maps.mask[0, 0]))
    return RelitPhoto(out, new, lit / max(mass, 1.0), albedo_out)


def _over_photo(linear: torch.Tensor, mask: torch.Tensor, photo: torch.Tensor, dtype: torch.dtype) -> torch.Tensor:
    """A band's relit person (1, h, w, 3) linear, sRGB-encoded over its photo (1, 3, h, w) sRGB by its
    mask (1, 1, h, w): (1, h, w, 3) in [0, 1], or levels 0-255 (float, rounded) for ``torch.uint8``."""
    fg = linear_to_srgb(linear.clamp(0, 1))
    band = composite(fg, to_channels_last(mask), to_channels_last(photo))
    if dtype == torch.uint8:
        check_finite(band, "relit image")
        band = band.clamp_(0, 1).mul_(255).round_()
    return band
