"""Job 1 of the pipeline: relight a photo of a person with any light (2D path).

predict (albedo, transport, light) at the model's working size around the person, paste
back at the original resolution, relight with the new light over the untouched background.
The albedo that is relit is the photo divided by the predicted shading
(:func:`~relightnet.model.photo_albedo`), so the photo keeps its detail; ``detail=False``
relights the CNN's own albedo (blurred to the working size on a large photo).

:func:`relight_prediction` is the relighting step itself on a pasted prediction (the 2D path of
``compare``, batches of frames); :func:`over_photo` puts its result over the photo.
``relight-image`` and ``relight-video`` compute the same in bands of rows without pasting the
maps whole (:mod:`relightnet.pipeline.relight_bands`: the memory budget at the pixel limit).
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass

import torch

from ..checks import check_finite, check_shape, sh_order_from_count
from ..color import linear_to_srgb, srgb_to_linear
from ..model.exposure import match_exposure
from ..model.network import Prediction
from ..model.photo_albedo import ROW_BAND, photo_albedo
from ..raster.interpolate import to_channels_first, to_channels_last
from ..render.shading import composite, shade
from ..sh.io import resize_sh
from .backends import as_predictor

logger = logging.getLogger(__name__)

__all__ = ["RelitImage", "Relit", "relight_image", "relight_prediction", "over_photo", "match_exposure",
           "to_model_order"]


@dataclass(frozen=True, eq=False)
class RelitImage:
    """Result of :func:`relight_image`: ``image`` (H, W, 3) sRGB in [0, 1], ``prediction`` (at the
    photo's resolution), the ``light`` actually used (K, 3), whether the mask came from the model,
    and the ``albedo`` that was relit (3, H, W) linear; ``prediction`` and ``albedo`` are None when
    :func:`relight_image` was asked for no maps."""

    image: torch.Tensor
    prediction: Prediction | None
    light: torch.Tensor
    mask_predicted: bool
    albedo: torch.Tensor | None


@dataclass(frozen=True, eq=False)
class Relit:
    """What :func:`relight_prediction` returns (CNN layout, linear RGB).

    Attributes:
        linear: (B, 3, H, W) the relit person A ⊙ (T · L′), zero where the maps are.
        albedo: (B, 3, H, W) the albedo that was relit.
        light: the light L′ used ((K, 3) or (B, K, 3); exposure-matched when asked).
        shading: (B, 3, H, W) its shading T · L′.
    """

    linear: torch.Tensor
    albedo: torch.Tensor
    light: torch.Tensor
    shading: torch.Tensor


def to_model_order(light: torch.Tensor, lmax: int) -> torch.Tensor:
    """(K, 3) light at the model's SH order ``lmax`` (zero-padded, or truncated with a warning)."""
    order = sh_order_from_count(light.shape[0], "light")
    if order > lmax:
        logger.warning("light: order %d truncated to the model's order %d", order, lmax)
    return resize_sh(light, lmax)


def relight_prediction(pred: Prediction, image: torch.Tensor, light: torch.Tensor, detail: bool = True,
                       keep_exposure: bool = True, reference: torch.Tensor | None = None) -> Relit:
    """Relight what the CNN predicted for a photo (or a batch of frames) with a new light.

    Args:
        pred: the :class:`Prediction` at the photo's resolution (a predictor's output), batch B.
        image: (B, 3, H, W) the photo, sRGB in [0, 1] (or uint8).
        light: (K, 3) or (B, K, 3) new light at the model's order, camera-relative light frame.
        detail: relight the photo's own albedo (photo / predicted shading,
            :func:`~relightnet.model.photo_albedo`); False relights the CNN's albedo.
        keep_exposure: scale the light so the person keeps the photo's exposure
            (:func:`~relightnet.model.exposure.match_exposure`, one factor for the batch).
        reference: (B, K, 3) the light taken as the photo's own (the exposure reference and the
            divisor of the photo albedo); default ``pred.light`` (a video passes its smoothed estimate).

    Returns:
        :class:`Relit`.
    """
    dims = check_shape(image, ["B", 3, "H", "W"], name="image")
    check_shape(pred.albedo, [dims["B"], 3, dims["H"], dims["W"]], name="prediction albedo")
    if image.dtype == torch.uint8:
        image = image.float() / 255
    ref = pred if reference is None else dataclasses.replace(pred, light=reference)
    before = ref.shading() if detail or keep_exposure else None
    new = match_exposure(light, ref, before) if keep_exposure else light
    albedo = photo_albedo(srgb_to_linear(image.to(pred.albedo)), ref, shading=before) if detail else pred.albedo
    linear, shading = shade(to_channels_last(albedo), to_channels_last(pred.transport), new.to(pred.albedo),
                            with_shading=True)
    return Relit(to_channels_first(linear), albedo, new, to_channels_first(shading))


def over_photo(relit: torch.Tensor, mask: torch.Tensor, image: torch.Tensor) -> torch.Tensor:
    """The relit person, sRGB-encoded, composited over the photo (the background kept as shot).

    Args:
        relit: (B, 3, H, W) linear (:attr:`Relit.linear`).
        mask: (B, 1, H, W) the person's coverage in [0, 1].
        image: (B, 3, H, W) the photo, sRGB in [0, 1].

    Returns:
        (B, H, W, 3) sRGB in [0, 1].
    """
    dims = check_shape(relit, ["B", 3, "H", "W"], name="relit")
    out = relit.new_empty(dims["B"], dims["H"], dims["W"], 3)
    for r in range(0, dims["H"], ROW_BAND):  # in bands of rows: a large photo's temporaries stay small
        band = slice(r, r + ROW_BAND)
        fg = to_channels_last(linear_to_srgb(relit[:, :, band].clamp(0, 1)))
        out[:, band] = composite(fg, to_channels_last(mask[:, :, band]), to_channels_last(image[:, :, band].to(fg)))
    return out


@torch.no_grad()
def relight_image(model, image: torch.Tensor, light: torch.Tensor, mask: torch.Tensor | None = None,
                  keep_exposure: bool = True, size: int | None = None, detail: bool = True,
                  maps: bool = True, soft_edges: bool = True) -> RelitImage:
    """Relight a photo.

    The photo is relit at its full size in bands of rows
    (:func:`~relightnet.pipeline.relight_bands.relight_over_photo`): with ``soft_edges=False`` the same
    result as :func:`relight_prediction` and :func:`over_photo` on the pasted prediction (to float32
    rounding), without holding the CNN's maps at the photo's size unless ``maps`` asks for them.

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
        :class:`RelitImage`; outside the mask the photo is unchanged.
    """
    from .relight_bands import relight_over_photo

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
    pred = crop.pasted() if maps else None
    return RelitImage(res.image, pred, res.light, mask is None, res.albedo)
