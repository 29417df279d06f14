"""One photo in the app: the CNN runs once, every change of light only re-shades.

:class:`RelightSession` holds what :func:`relightnet.pipeline.relight_prediction` needs that does
not depend on the new light — the prediction (transport T), the photo's albedo (photo / T·L̂)
and the person's mean shading luminance under the photo's own light (the exposure reference) —
so :meth:`RelightSession.relight` is one T·L′ product, one scale, one multiply and the
sRGB composite over the photo: the same result as ``relightnet relight-image`` for the same
light (the same functions, in the same order), at interactive speed.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import torch

from ..checks import InputError, check_finite, check_shape
from ..color import linear_to_srgb, luminance, srgb_to_linear
from ..model.network import Prediction, photo_albedo, shading_map
from ..render.shading import composite, to_channels_last
from .. import sh as _sh

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


class RelightSession:
    """A photo with its prediction, ready to be relit many times.

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
        image = photo.image[None].to(pred.albedo)
        before = pred.shading()
        self._albedo = photo_albedo(srgb_to_linear(image), pred, shading=before)  # (1, 3, H, W)
        m = pred.mask
        self._mask_sum = m.sum().clamp_min(1)
        self._level = float((luminance(to_channels_last(before))[:, None] * m).sum() / self._mask_sum)
        self._fg_alpha = to_channels_last(m)
        self._bg = to_channels_last(image)

    @property
    def light(self) -> torch.Tensor:
        """(K, 3) the light the CNN estimated for the photo."""
        return self.prediction.light[0]

    @torch.no_grad()
    def relight(self, light: torch.Tensor, keep_exposure: bool = True) -> torch.Tensor:
        """The photo relit with a new light (as ``relight-image``: detail kept, exposure matched).

        Args:
            light: (K, 3) camera-relative linear RGB light (resized to the model's order).
            keep_exposure: scale the light so the person keeps the photo's exposure.

        Returns:
            (H, W, 3) sRGB in [0, 1].
        """
        check_shape(light, ["K", 3], name="light")
        check_finite(light, "light")
        light = _sh.resize_sh(light.float(), self.lmax).to(self._albedo)
        s = shading_map(self.prediction.transport, light)  # (1, 3, H, W)
        if keep_exposure:
            new = float((luminance(to_channels_last(s))[:, None] * self.prediction.mask).sum() / self._mask_sum)
            if new > 1e-8 and self._level > 0:
                s = s * (self._level / new)
        fg = to_channels_last(linear_to_srgb((self._albedo * s).clamp(0, 1)))
        return composite(fg, self._fg_alpha, self._bg)[0]

    def mask_overlay(self) -> torch.Tensor:
        """(H, W, 3) sRGB: the photo with the person's mask tinted, for viewing."""
        m = self.prediction.mask[0, 0][..., None]
        tint = torch.tensor([0.1, 0.8, 0.3])
        img = self.photo.image.permute(1, 2, 0)
        return img * (1 - 0.5 * m) + 0.5 * m * tint
