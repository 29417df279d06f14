"""Training losses of the inverse-rendering CNN (Kanamori & Endo 2018's set, weighted by a config).

With ground truth (A, T, L), the image I = A ⊙ S(T, L) and predictions (Â, T̂, L̂), all
masked by the person mask M and averaged over masked pixels:

- direct: |T̂ − T|, |Â − A| (pixels), |L̂ − L| (coefficients);
- shading: |S(T̂, L) − S(T, L)|, |S(T, L̂) − S(T, L)|, |S(T̂, L̂) − S(T, L)|;
- rendering: |Â ⊙ S(T̂, L̂) − I|, |Â ⊙ S(T, L) − I|, |A ⊙ S(T̂, L̂) − I|. KE18's released
  code computed one rendering term with the shading of a different term (a copy-paste of
  the wrong shading variable); here every term uses its own shading;
- relighting (off by default): |Â ⊙ S(T̂, L′) − A ⊙ S(T, L′)| with L′ the batch's ``novel_light``
  when it has one (:func:`relightnet.model.round_trip.novel_lights`), else the light of another
  item of the batch (rolled by one), what the model is used for: a new light;
- total variation of T̂ and Â inside the eroded mask;
- mask: binary cross-entropy of the mask head against M (when present);
- light head (``hybrid`` networks): |L̂_head − L|, so that the solve's prior is a light too;
- light shape (off by default): the scale-invariant irradiance error of L̂ against L over the
  sphere (:func:`relightnet.sh.metrics.scale_invariant_light_error`): direction and colour, not
  exposure.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
from torch.nn import functional as F

from ..raster.morphology import erode
from ..sh.metrics import scale_invariant_light_error
from .maps import shading_map
from .network import Prediction

__all__ = ["LossWeights", "masked_l1", "total_variation", "relight_losses"]


@dataclass(frozen=True)
class LossWeights:
    """Weights of the loss terms of the module docstring, in its order (0 turns a term off): the direct
    terms, the shading terms ``shading_t/_l/_tl``, the rendering terms ``render_al/_a/_tl``,
    ``relit_novel``, ``tv``, ``mask``, ``light_head``, ``light_si`` (the scale-invariant light shape) and
    ``round_trip`` (the training loop's second pass, :func:`relightnet.model.round_trip.round_trip_loss`)."""

    transport: float = 1.0
    albedo: float = 1.0
    light: float = 1.0
    shading_t: float = 1.0
    shading_l: float = 1.0
    shading_tl: float = 1.0
    render_al: float = 1.0
    render_a: float = 1.0
    render_tl: float = 1.0
    relit_novel: float = 0.0
    tv: float = 0.05
    mask: float = 0.5
    light_head: float = 0.0
    light_si: float = 0.0
    round_trip: float = 0.0

    def to_dict(self) -> dict:
        return asdict(self)


def masked_l1(a: torch.Tensor, b: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Mean |a − b| over masked pixels (and channels). a, b: (B, C, H, W); mask: (B, 1, H, W)."""
    num = ((a - b).abs() * mask).sum()
    return num / (mask.sum() * a.shape[1]).clamp_min(1.0)


def total_variation(x: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Mean absolute horizontal + vertical differences of (B, C, H, W) inside (B, 1, H, W)."""
    dx = (x[..., :, 1:] - x[..., :, :-1]).abs() * (mask[..., :, 1:] * mask[..., :, :-1])
    dy = (x[..., 1:, :] - x[..., :-1, :]).abs() * (mask[..., 1:, :] * mask[..., :-1, :])
    return (dx.sum() + dy.sum()) / (mask.sum() * x.shape[1]).clamp_min(1.0)


def relight_losses(pred: Prediction, batch: dict, weights: LossWeights = LossWeights()) -> dict:
    """All loss terms and their weighted total.

    Args:
        pred: network output.
        batch: ``image`` (B, 3, H, W) linear, ``mask`` (B, 1, H, W), ``albedo`` (B, 3, H, W),
            ``transport`` (B, K, H, W), ``light`` (B, K, 3); optional ``render`` (B, 3, H, W): the
            image the rendering terms aim at (default ``image``); optional ``novel_light`` (B, K, 3):
            the lights of ``relit_novel`` (default the batch's lights rolled by one item).
        weights: per-term weights (0 disables a term).

    Returns:
        dict of scalar tensors, including ``total``.
    """
    M = batch["mask"]
    I, A, T, L = batch.get("render", batch["image"]), batch["albedo"], batch["transport"], batch["light"]
    Ah, Th, Lh = pred.albedo.float(), pred.transport.float(), pred.light.float()
    S = shading_map(T, L)
    S_tl = shading_map(Th, Lh)
    terms = {
        "transport": masked_l1(Th, T, M),
        "albedo": masked_l1(Ah, A, M),
        "light": (Lh - L).abs().mean(),
        "shading_t": masked_l1(shading_map(Th, L), S, M),
        "shading_l": masked_l1(shading_map(T, Lh), S, M),
        "shading_tl": masked_l1(S_tl, S, M),
        "render_al": masked_l1(Ah * S_tl, I, M),
        "render_a": masked_l1(Ah * S, I, M),
        "render_tl": masked_l1(A * S_tl, I, M),
    }
    if weights.relit_novel:
        L_new = batch["novel_light"] if "novel_light" in batch else L.roll(1, 0)  # another item's light
        terms["relit_novel"] = masked_l1(Ah * shading_map(Th, L_new), A * shading_map(T, L_new), M)
    inner = erode(M)
    terms["tv"] = total_variation(Th, inner) + total_variation(Ah, inner)
    if pred.mask is not None:
        terms["mask"] = F.binary_cross_entropy(pred.mask.float().clamp(1e-6, 1 - 1e-6), M)
    if weights.light_si:
        terms["light_si"] = scale_invariant_light_error(Lh, L).mean()
    if pred.light_head is not None and weights.light_head:
        terms["light_head"] = (pred.light_head.float() - L).abs().mean()
    w = weights.to_dict()
    terms["total"] = sum(w[k] * v for k, v in terms.items() if w.get(k, 0.0))
    return terms
