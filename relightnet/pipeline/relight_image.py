"""Job 1 of the pipeline: relight a photo of a person with any light (2D path).

predict (albedo, transport, light) at the model's working size around the person, then relight at
the photo's own resolution with the new light over the untouched background, in bands of rows
(:func:`~relightnet.pipeline.relight_bands.relight_over_photo`, the package's one photo relight: the
CNN's maps are never pasted whole, the memory budget at the pixel limit).
The albedo that is relit is the photo divided by the predicted shading
(:func:`~relightnet.model.photo_albedo`), so the photo keeps its detail; ``detail=False``
relights the CNN's own albedo (blurred to the working size on a large photo).
"""

from __future__ import annotations

import dataclasses
import logging

import torch

from ..checks import check_finite, check_shape, sh_order_from_count
from ..model.exposure import match_exposure
from ..sh.io import resize_sh
from .backends import as_predictor
from .relight_bands import RelitPhoto, relight_over_photo

logger = logging.getLogger(__name__)

__all__ = ["relight_image", "match_exposure", "to_model_order"]


def to_model_order(light: torch.Tensor, lmax: int) -> torch.Tensor:
    """(K, 3) light at the model's SH order ``lmax`` (zero-padded, or truncated with a warning)."""
    order = sh_order_from_count(light.shape[0], "light")
    if order > lmax:
        logger.warning("light: order %d truncated to the model's order %d", order, lmax)
    return resize_sh(light, lmax)


@torch.no_grad()
def relight_image(model, image: torch.Tensor, light: torch.Tensor, mask: torch.Tensor | None = None,
                  keep_exposure: bool = True, size: int | None = None, detail: bool = True,
                  maps: bool = True, soft_edges: bool = True) -> RelitPhoto:
    """Relight a photo.

    The photo is relit at its full size in bands of rows
    (:func:`~relightnet.pipeline.relight_bands.relight_over_photo`), without holding the CNN's maps
    at the photo's size unless ``maps`` asks for them.

    Args:
        model: the CNN: a :class:`~relightnet.model.RelightNet` (e.g. ``relightnet.model.load_model()``)
            or a :class:`~relightnet.pipeline.backends.Predictor` (torch or ONNX backend).
        image: (3, H, W) sRGB in [0, 1] (or uint8).
        light: (K, 3) new light, camera-relative light frame, linear RGB.
        mask: (H, W) person mask; None uses the model's mask head.
        keep_exposure: scale the light so the person keeps the photo's exposure.
        size: working size (default: the model's, from its checkpoint); only with a RelightNet.
        detail: relight the photo's own albedo (photo / predicted shading, full detail); False
            relights the CNN's albedo.
        maps: also return the prediction and the relit albedo at the photo's size (about
            0.06 GB per megapixel more; ``relight-image --save-maps``).
        soft_edges: a soft matte in the person's border band (:func:`~relightnet.segment.matte.soft_composite`);
            False pastes the person with the mask as it is (a cut-out's own alpha, ``--hard-edges``).

    Returns:
        :class:`~relightnet.pipeline.relight_bands.RelitPhoto` with its ``prediction`` (when ``maps``)
        and ``mask_predicted``; outside the mask the photo is unchanged.
    """
    check_shape(light, ["K", 3], name="light")
    check_finite(light, "light")
    predict = as_predictor(model, size=size)
    light = to_model_order(light, predict.lmax)
    crop = predict.crop(image, mask)
    res = relight_over_photo(crop, image, light, detail=detail, keep_exposure=keep_exposure, keep_albedo=maps,
                             soft_edges=soft_edges)
    if res.lit < 0.5:
        logger.warning("light: it lights only %.0f%% of the person (negative or zero irradiance elsewhere): "
                       "is it a valid SH light?", 100 * res.lit)
    return dataclasses.replace(res, prediction=crop.pasted() if maps else None, mask_predicted=mask is None)
