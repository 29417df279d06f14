"""One photo in the app: the CNN runs once, every change of light only re-shades.

:class:`RelightSession` holds what the photo relight (:func:`relightnet.pipeline.relight_over_photo`)
needs that does not depend on the new light — the prediction (transport T), the photo's albedo (photo / T·L̂)
and the person's mean shading luminance under the photo's own light (the exposure reference) —
so :meth:`RelightSession.relight` is one T·L′ product, one scale, one multiply and the
sRGB composite over the photo, inside the person's bounding box only: the same result as
``relightnet relight-image`` for the same light (the same formulas, in the same order), at
interactive speed.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import torch

from ..checks import InputError, check_finite, check_shape
from ..color import linear_to_srgb, srgb_to_linear
from ..model.exposure import exposure_level, exposure_scale, transport_level
from ..model.network import Prediction
from ..model.photo_albedo import photo_albedo
from ..segment.matte import edge_matte, soft_composite
from ..sh.io import resize_sh

__all__ = ["Photo", "load_photo", "RelightSession"]


@dataclass(frozen=True, eq=False)
class Photo:
    """A decoded photo: ``image`` (3, H, W) sRGB in [0, 1], ``mask`` (H, W) the person's, ``alpha``
    (H, W) or None (a cut-out's transparency, which is also its mask)."""

    image: torch.Tensor
    mask: torch.Tensor
    alpha: torch.Tensor | None


def load_photo(path) -> Photo:
    """Read a photo within the pixel limit and find the person: its alpha if it is a cut-out, else
    the person segmentation (:func:`relightnet.segment.sources.person_mask`), as the CLI does.

    Raises:
        InputError: unreadable, over the pixel limit (the CLI's message) or no person found.
    """
    from ..io import read_image_alpha
    from ..io.probe import check_image_file
    from ..segment.sources import person_mask

    path = Path(path)
    check_image_file(path, "an image")
    img, alpha = read_image_alpha(path)
    img = img.permute(2, 0, 1).contiguous()
    mask = person_mask(img, None, alpha, "segment", name=str(path))
    if not bool(mask.any()):
        raise InputError(f"{path.name}: no person found in the photo")
    return Photo(img, mask, alpha)


#: Entries of the sRGB lookup table of the live view (the encoding of linear values i / (N − 1)):
#: nearest-entry error under 0.05 of an 8-bit level.
_LUT_SIZE = 1 << 16


class RelightSession:
    """A photo with its prediction, ready to be relit many times.

    Only the person's bounding box is re-shaded; the exposure reference is linear in the light
    (the mean luminance of T · L′ over the mask is ``luminance(W L′)`` with W (K,) the
    mask-weighted sum of the transport, precomputed), so a change of light costs one (3, K) × (K, N)
    product over the N pixels of the box, one multiply and the composite.

    Args:
        predictor: a :class:`~relightnet.pipeline.backends.Predictor` or a RelightNet.
        photo: :class:`Photo`.
    """

    def __init__(self, predictor, photo: Photo):
        from ..pipeline.backends import as_predictor

        predict = as_predictor(predictor)
        self.lmax = predict.lmax
        self.photo = photo
        with torch.no_grad():
            pred: Prediction = predict(photo.image, photo.mask)
            self.prediction = pred
            self._prepare(pred, photo.image[None].to(pred.albedo))

    def _prepare(self, pred: Prediction, image: torch.Tensor) -> None:
        before = pred.shading()
        albedo = photo_albedo(srgb_to_linear(image), pred, shading=before)  # (1, 3, H, W)
        m = pred.mask[0, 0]
        rows, cols = torch.nonzero(m.sum(1) > 0)[:, 0], torch.nonzero(m.sum(0) > 0)[:, 0]
        if rows.numel() == 0:
            raise InputError("photo: the person's mask is empty")
        self._box = (int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1)
        y0, y1, x0, x1 = self._box

        def box(t):  # (1, C, H, W) → (C, N) inside the box
            return t[0, :, y0:y1, x0:x1].reshape(t.shape[1], -1).contiguous()

        self._transport, self._albedo = box(pred.transport), box(albedo)
        self._alpha, self._bg = box(pred.mask), box(image)
        mask_sum = m.sum().clamp_min(1)
        self._weights = (self._transport.double() * self._alpha.double()).sum(1) / mask_sum  # (K,)
        self._level = float(exposure_level(before, pred.mask))
        self._photo_hwc = image[0].permute(1, 2, 0).contiguous()
        self._photo_u8 = (self._photo_hwc * 255).round().to(torch.uint8)
        self._lut = linear_to_srgb(torch.linspace(0, 1, _LUT_SIZE, dtype=image.dtype))
        # the soft border band, as relight-image composites it (a cut-out keeps its own alpha)
        self._edge = edge_matte(image[0], m) if self.photo.alpha is None else None

    @property
    def light(self) -> torch.Tensor:
        """(K, 3) the light the CNN estimated for the photo."""
        return self.prediction.light[0]

    def _box_srgb(self, light: torch.Tensor, keep_exposure: bool, exact: bool) -> torch.Tensor:
        """(3, N) the composite over the box, sRGB in [0, 1]."""
        check_shape(light, ["K", 3], name="light")
        check_finite(light, "light")
        light = resize_sh(light.float(), self.lmax).to(self._albedo)
        s = light.T @ self._transport  # (3, N) = T · L′
        if keep_exposure:
            s.mul_(float(exposure_scale(self._level, transport_level(self._weights, light))))
        lin = s.mul_(self._albedo).clamp_(0, 1)  # in place: one buffer for the whole chain
        fg = linear_to_srgb(lin) if exact else self._lut[lin.mul_(_LUT_SIZE - 1).round_().to(torch.int32)]
        return fg.sub_(self._bg).mul_(self._alpha).add_(self._bg)  # lerp(bg, fg, α)

    @torch.no_grad()
    def relight(self, light: torch.Tensor, keep_exposure: bool = True) -> torch.Tensor:
        """The photo relit with a new light, as ``relight-image`` computes it (detail kept, exposure matched).

        Args:
            light: (K, 3) camera-relative linear RGB light (resized to the model's order).
            keep_exposure: scale the light so the person keeps the photo's exposure.

        Returns:
            (H, W, 3) sRGB in [0, 1].
        """
        y0, y1, x0, x1 = self._box
        out = self._photo_hwc.clone()
        out[y0:y1, x0:x1] = self._box_srgb(light, keep_exposure, True).T.reshape(y1 - y0, x1 - x0, 3)
        return soft_composite(out, self._edge)

    @torch.no_grad()
    def relight_u8(self, light: torch.Tensor, keep_exposure: bool = True) -> torch.Tensor:
        """:meth:`relight` for the live view: (H, W, 3) uint8, the sRGB curve from a lookup table
        (within one 8-bit level of :meth:`relight` quantised)."""
        y0, y1, x0, x1 = self._box
        box = self._box_srgb(light, keep_exposure, False).T.reshape(y1 - y0, x1 - x0, 3)
        if self._edge is None:
            out = self._photo_u8.clone()
            out[y0:y1, x0:x1] = box.mul_(255).round_().to(torch.uint8)
            return out
        out = self._photo_hwc.clone()  # the soft band from float values, then one rounding
        out[y0:y1, x0:x1] = box
        return soft_composite(out, self._edge).mul_(255).round_().to(torch.uint8)

    def mask_overlay(self) -> torch.Tensor:
        """(H, W, 3) sRGB: the photo with the person's mask tinted, for viewing."""
        m = self.prediction.mask[0, 0][..., None]
        tint = torch.tensor([0.1, 0.8, 0.3])
        img = self.photo.image.permute(1, 2, 0)
        return img * (1 - 0.5 * m) + 0.5 * m * tint
