"""Job 1 of the pipeline: relight a photo of a person with any light (2D path).

predict (albedo, transport, light) at the model's working size around the person, paste
back at the original resolution, relight with the new light over the untouched background.
The albedo that is relit is the photo divided by the predicted shading
(:func:`~relightnet.model.photo_albedo`), so the photo keeps its detail; ``detail=False``
relights the CNN's own albedo (blurred to the working size on a large photo).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import torch

from ..checks import check_finite, check_shape, sh_order_from_count
from ..io.image import linear_to_srgb, srgb_to_linear
from ..model.inference import predict_image
from ..model.network import Prediction, RelightNet, photo_albedo, shading_map
from ..sh.io import resize_sh

logger = logging.getLogger(__name__)

__all__ = ["RelitImage", "relight_image", "match_exposure", "to_model_order"]


@dataclass(frozen=True, eq=False)
class RelitImage:
    """Result of :func:`relight_image`: ``image`` (H, W, 3) sRGB in [0, 1], ``prediction``,
    the ``light`` actually used (K, 3), whether the mask came from the model, and the
    ``albedo`` that was relit (3, H, W) linear."""

    image: torch.Tensor
    prediction: Prediction
    light: torch.Tensor
    mask_predicted: bool
    albedo: torch.Tensor


def match_exposure(new_light: torch.Tensor, pred: Prediction, shading: torch.Tensor | None = None) -> torch.Tensor:
    """Scale ``new_light`` (K, 3) so the person's mean shading luminance stays what it was.

    Lights come at any scale (a projected HDRI's sun reaches 1e4); matching the exposure keeps
    the relit person as bright as in the photo while the direction and colour of light change.
    ``shading``: ``pred.shading()`` (B, 3, H, W) when the caller has it already.
    """
    m = pred.mask
    lum = torch.tensor([0.2126, 0.7152, 0.0722])

    def level(s):
        return float((torch.einsum("bchw,c->bhw", s, lum.to(s))[:, None] * m).sum() / m.sum().clamp_min(1))

    old = level(pred.shading() if shading is None else shading)
    new = level(shading_map(pred.transport, new_light.to(pred.transport)))
    return new_light * (old / new) if new > 1e-8 and old > 0 else new_light


def to_model_order(light: torch.Tensor, lmax: int) -> torch.Tensor:
    """(K, 3) light at the model's SH order ``lmax`` (zero-padded, or truncated with a warning)."""
    order = sh_order_from_count(light.shape[0], "light")
    if order > lmax:
        logger.warning("light: order %d truncated to the model's order %d", order, lmax)
    return resize_sh(light, lmax)


@torch.no_grad()
def relight_image(model: RelightNet, image: torch.Tensor, light: torch.Tensor, mask: torch.Tensor | None = None,
                  keep_exposure: bool = True, size: int | None = None, detail: bool = True) -> RelitImage:
    """Relight a photo.

    Args:
        model: the CNN (e.g. ``relightnet.model.load_model()``).
        image: (3, H, W) sRGB in [0, 1] (or uint8).
        light: (K, 3) new light, camera-relative light frame, linear RGB.
        mask: (H, W) person mask; None uses the model's mask head.
        keep_exposure: scale the light so the person keeps the photo's exposure.
        size: working size (default: the model's training size).
        detail: relight the photo's own albedo (photo / predicted shading, full detail); False
            relights the CNN's albedo.

    Returns:
        :class:`RelitImage`; outside the mask the photo is unchanged.
    """
    check_shape(light, ["K", 3], name="light")
    check_finite(light, "light")
    light = to_model_order(light, model.config.lmax)
    if image.dtype == torch.uint8:
        image = image.float() / 255
    pred, _ = predict_image(model, image, mask, size=size)
    before = pred.shading()
    new = match_exposure(light, pred, before) if keep_exposure else light
    image = image.to(pred.albedo)
    albedo = photo_albedo(srgb_to_linear(image)[None], pred, shading=before) if detail else pred.albedo
    shading = shading_map(pred.transport, new.to(pred.albedo))
    relit = (albedo * shading)[0]
    lit = float(((shading.mean(1, keepdim=True) > 0).float() * pred.mask).sum() / pred.mask.sum().clamp_min(1))
    if lit < 0.5:
        logger.warning("light: it lights only %.0f%% of the person (negative or zero irradiance elsewhere): "
                       "is it a valid SH light?", 100 * lit)
    m = pred.mask[0]
    out = linear_to_srgb(relit.clamp(0, 1)) * m + image * (1 - m)  # background kept as shot
    return RelitImage(out.permute(1, 2, 0).cpu(), pred, new, mask is None, albedo[0].cpu())

