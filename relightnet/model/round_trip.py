"""Training terms that ask a network to relight what it sees, and to see the light it relit with.

A user relights a photo with the network's own maps (``relight-image``: the photo's albedo,
photo ÷ predicted shading, times the new shading, the exposure kept) and may estimate the light
of the result again (``evaluate photos``' round trip, :func:`relightnet.pipeline.photo_checks.check_photo`).
Training on the generated people alone never shows the network such a relit photo. The terms here
build it inside a training step, from the network input and its prediction:

- :func:`novel_lights`: the lights an item is relit with, per item either a strong white light
  from one direction (``power · Y(d) + ambient``, d in the camera's half of the sphere, as the
  side contrast's lights are) or the light of another item of the batch;
- :func:`relit_input`: the network input of the item relit to such a light with the network's
  own maps (no gradient: it is a new photo, not a path to the first prediction);
- :func:`round_trip_loss`: the scale-invariant irradiance error of the light the network reads
  back from that input (:func:`relightnet.sh.scale_invariant_light_error`, whole sphere).
"""

from __future__ import annotations

import dataclasses

import torch

from ..checks import InputError, check_shape
from ..color import linear_to_srgb, srgb_to_linear
from ..light import side_light
from ..sh import scale_invariant_light_error
from .exposure import match_exposure
from .maps import relight
from .network import Prediction, normalize_input
from .photo_albedo import photo_albedo

__all__ = ["NOVEL_LIGHTS", "novel_lights", "relit_input", "round_trip_loss"]

#: How the lights of the novel-light terms are drawn: ``batch`` (another item's light) or
#: ``side`` (half of the items a strong directional light, the others another item's light).
NOVEL_LIGHTS = ("batch", "side")


def novel_lights(light: torch.Tensor, kind: str, generator: torch.Generator | None = None,
                 power: tuple[float, float] = (1.0, 4.0), ambient: tuple[float, float] = (0.1, 0.5)) -> torch.Tensor:
    """New lights for a batch whose own lights are ``light``.

    Args:
        light: (B, K, 3) the items' lights.
        kind: one of :data:`NOVEL_LIGHTS`.
        generator: draws of ``side`` (directions uniform on the camera's half of the sphere, x ≥ 0 in
            the light frame; power and ambient uniform in their ranges; each item a coin toss).
        power, ambient: ranges of ``side``'s white directional light and of its l = 0 ambient.

    Returns:
        (B, K, 3) float32: ``light`` rolled by one item (``batch``), or per item either that or
        ``power · Y(d) + ambient`` (:func:`relightnet.light.side_light`).
    """
    dims = check_shape(light, ["B", "K", 3], name="light")
    if kind not in NOVEL_LIGHTS:
        raise InputError(f"novel_light: expected one of {', '.join(NOVEL_LIGHTS)}, got {kind!r}")
    rolled = light.roll(1, 0).float()
    if kind == "batch":
        return rolled
    lmax = round(dims["K"] ** 0.5) - 1
    u = torch.rand(dims["B"], 4, generator=generator, dtype=torch.float64)  # column 3 unused; kept so draws repeat
    d = torch.randn(dims["B"], 3, generator=generator, dtype=torch.float64)
    d[:, 0] = d[:, 0].abs()
    out = rolled.clone()
    for i in range(dims["B"]):
        if u[i, 0] < 0.5:
            p = power[0] + (power[1] - power[0]) * float(u[i, 1])
            a = ambient[0] + (ambient[1] - ambient[0]) * float(u[i, 2])
            out[i] = side_light(d[i], p, a, lmax).to(out)
    return out


@torch.no_grad()
def relit_input(x: torch.Tensor, pred: Prediction, light: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """The network input ``x`` relit to ``light`` with the network's own maps, as ``relight-image`` relights.

    Inside the input's mask the photo's albedo (photo ÷ predicted shading,
    :func:`~relightnet.model.photo_albedo`) is shaded by ``T̂ · light``, each item's light scaled so that
    its mean shading over the mask equals that of the predicted light (the exposure kept:
    :func:`~relightnet.model.exposure.match_exposure` per item).

    Args:
        x: (B, 4, S, S) network input (:func:`~relightnet.model.normalize_input`: sRGB·2 − 1 inside the mask, mask).
        pred: the network's :class:`Prediction` for ``x`` (at S × S).
        light: (B, K, 3) the new lights.

    Returns:
        ``(x', light')``: (B, 4, S, S) the relit input (same mask) and (B, K, 3) the lights as scaled.
    """
    dims = check_shape(x, ["B", 4, "S", "S"], name="x")
    check_shape(light, [dims["B"], pred.transport.shape[1], 3], name="light")
    mask = x[:, 3:].float()
    srgb = ((x[:, :3].float() / mask.clamp_min(1e-6) + 1) / 2).clamp(0, 1)
    ref = Prediction(pred.albedo.float(), pred.transport.float(), pred.light.float(), mask)
    before = ref.shading()
    scaled = match_exposure(light.float(), ref, before, per_item=True)
    albedo = photo_albedo(srgb_to_linear(srgb), ref, shading=before)
    relit = linear_to_srgb(relight(dataclasses.replace(ref, albedo=albedo), scaled).clamp(0, 1))
    return normalize_input(relit, mask).to(x.dtype), scaled


def round_trip_loss(model, x: torch.Tensor, pred: Prediction, light: torch.Tensor) -> torch.Tensor:
    """Mean scale-invariant error of the light ``model`` reads from ``x`` relit to ``light`` (:func:`relit_input`).

    Args:
        model: the network (called on the relit input; its gradient flows through this second pass only).
        x: (B, 4, S, S) network input; pred: its prediction; light: (B, K, 3) the new lights.

    Returns:
        () scalar.
    """
    x2, scaled = relit_input(x, pred, light)
    back = model(x2).light.float()
    return scale_invariant_light_error(back, scaled).mean()
