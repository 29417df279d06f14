"""Running the CNN on real images: KE18-style crop, resize, predict, paste back.

A photo of any size is cropped to the mask's bounding box with padding (made square, as
the training data is framed), resized to the model's working size, run through the
network, and the per-pixel maps are resized back into the original frame.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import torch
from torch.nn import functional as F

from ..checks import InputError, check_shape
from .network import Prediction, RelightNet, normalize_input

logger = logging.getLogger(__name__)

__all__ = ["CropBox", "mask_crop_box", "crop_to_box", "paste_from_box", "paste_rows", "frame_person", "predict_image",
           "CropMaps", "predict_crop", "estimate_light", "estimate_light_evidence", "check_not_blank",
           "check_predicted_person"]


@dataclass(frozen=True)
class CropBox:
    """A square crop (top, left, size) in pixels of the original image; may extend past its borders."""

    top: int
    left: int
    size: int


def mask_crop_box(mask: torch.Tensor, pad: float = 0.05) -> CropBox:
    """Square box around the mask's bounding box, padded by ``pad`` × its larger side.

    Args:
        mask: (H, W) in [0, 1].
    """
    check_shape(mask, ["H", "W"], name="mask")
    ys, xs = torch.nonzero(mask > 0.5, as_tuple=True)
    if ys.numel() == 0:
        raise InputError("mask: empty (no pixel above 0.5): expected a mask of the person")
    y0, y1, x0, x1 = int(ys.min()), int(ys.max()) + 1, int(xs.min()), int(xs.max()) + 1
    side = max(y1 - y0, x1 - x0)
    size = max(16, int(round(side * (1 + 2 * pad))))
    cy, cx = (y0 + y1) / 2, (x0 + x1) / 2
    return CropBox(int(round(cy - size / 2)), int(round(cx - size / 2)), size)


def crop_to_box(x: torch.Tensor, box: CropBox) -> torch.Tensor:
    """Cut a square box out of images: (B, C, H, W) → (B, C, size, size), zero outside the image."""
    h, w = x.shape[-2:]
    t, l, s = box.top, box.left, box.size
    out = x.new_zeros(*x.shape[:-2], s, s)
    ys, ye, xs, xe = max(t, 0), min(t + s, h), max(l, 0), min(l + s, w)
    if ys < ye and xs < xe:
        out[..., ys - t : ye - t, xs - l : xe - l] = x[..., ys:ye, xs:xe]
    return out


def paste_from_box(x: torch.Tensor, box: CropBox, h: int, w: int) -> torch.Tensor:
    """Inverse of :func:`crop_to_box` for maps at any working size: resized back to ``box.size``
    (bilinear) and placed in an (H, W) frame, zero outside the box: (B, C, s, s) → (B, C, H, W).

    One channel is resized at a time (the same values): a large photo's box resized with all
    its channels at once (a transport's K = 9) would double the peak memory of the paste."""
    out = x.new_zeros(*x.shape[:-2], h, w)
    t, l, s = box.top, box.left, box.size
    ys, ye, xs, xe = max(t, 0), min(t + s, h), max(l, 0), min(l + s, w)
    if ys < ye and xs < xe:
        for c in range(x.shape[-3]):
            up = F.interpolate(x[..., c : c + 1, :, :], size=(s, s), mode="bilinear", align_corners=False)
            out[..., c : c + 1, ys:ye, xs:xe] = up[..., ys - t : ye - t, xs - l : xe - l]
    return out


def paste_rows(x: torch.Tensor, box: CropBox, h: int, w: int, r0: int, r1: int,
               cols: tuple[int, int] | None = None) -> torch.Tensor:
    """Rows ``r0:r1`` of :func:`paste_from_box` ``(x, box, h, w)`` without the others: (B, C, s, s) →
    (B, C, r1 - r0, W), so a large photo's maps can be pasted one band of rows at a time; ``cols``
    (c0, c1) keeps columns ``c0:c1`` only: (B, C, r1 - r0, c1 - c0), the same values.

    The bilinear resize is torch's (``align_corners=False``): across, ``F.interpolate`` on the source
    rows the band needs; down, the same source positions and weights, computed here (equal to
    float32 rounding of the source position: within ~1e-5 of the maps' values)."""
    c0, c1 = (0, w) if cols is None else cols
    out = x.new_zeros(*x.shape[:-2], r1 - r0, c1 - c0)
    t, l, s, n = box.top, box.left, box.size, x.shape[-2]
    ys, ye, xs, xe = max(t, r0, 0), min(t + s, r1, h), max(l, c0, 0), min(l + s, c1, w)
    if ys >= ye or xs >= xe:
        return out
    scale = torch.tensor(n, dtype=torch.float32) / s
    src = (scale * (torch.arange(ys - t, ye - t, dtype=torch.float32) + 0.5) - 0.5).clamp_min(0)
    i0 = src.long().clamp_max(n - 1)
    i1 = (i0 + 1).clamp_max(n - 1)
    l1 = (src - i0).clamp(0, 1)[:, None].to(x.dtype)
    lo, hi = int(i0[0]), int(i1[-1]) + 1
    across = F.interpolate(x[..., lo:hi, :], size=(hi - lo, s), mode="bilinear", align_corners=False)
    across = across[..., xs - l : xe - l]
    band = across.index_select(-2, i0 - lo).mul_(1 - l1)
    out[..., ys - r0 : ye - r0, xs - c0 : xe - c0] = band.addcmul_(across.index_select(-2, i1 - lo), l1)
    return out


@dataclass(frozen=True, eq=False)
class CropMaps:
    """What the CNN predicted for a photo, kept at its working size with the crop box it saw.

    The maps at the photo's resolution are made on demand: :meth:`rows` pastes one band of rows
    (what a large photo is relit by, :func:`relightnet.pipeline.relight_bands.relight_over_photo`),
    :meth:`pasted` the whole :class:`Prediction` (:func:`predict_image`'s).

    Attributes:
        albedo: (1, 3, s, s) and ``transport`` (1, K, s, s) at the working size s.
        light: (1, K, 3); ``evidence`` and ``light_head`` as in :class:`Prediction`.
        mask: (1, 1, H, W) the person's mask at the photo's resolution (given or predicted).
        box: the crop of the photo the network saw.
    """

    albedo: torch.Tensor
    transport: torch.Tensor
    light: torch.Tensor
    mask: torch.Tensor
    box: CropBox
    evidence: object = None
    light_head: torch.Tensor | None = None

    @property
    def size(self) -> tuple[int, int]:
        """(H, W) of the photo."""
        return int(self.mask.shape[-2]), int(self.mask.shape[-1])

    def rows(self, r0: int, r1: int, albedo: bool = True, cols: tuple[int, int] | None = None):
        """``(albedo (1, 3, r, W) or None, transport (1, K, r, W), mask (1, 1, r, W))`` of rows ``r0:r1``,
        the maps zero outside the person's mask (times the mask, as :meth:`pasted`); ``cols`` (c0, c1):
        columns ``c0:c1`` only (width c1 - c0)."""
        h, w = self.size
        c0, c1 = (0, w) if cols is None else cols
        m = self.mask[:, :, r0:r1, c0:c1]
        t = paste_rows(self.transport, self.box, h, w, r0, r1, cols).mul_(m)
        a = paste_rows(self.albedo, self.box, h, w, r0, r1, cols).mul_(m) if albedo else None
        return a, t, m

    def span(self) -> tuple[int, int, int, int] | None:
        """``(r0, r1, c0, c1)``: the rows and columns of the photo holding every pixel of the mask above 0
        (ends exclusive), or None for an empty mask. Outside them the maps are zero."""
        m = self.mask[0, 0] > 0
        rows, cols = torch.nonzero(m.any(1)), torch.nonzero(m.any(0))
        if len(rows) == 0:
            return None
        return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1

    def pasted(self) -> Prediction:
        """The :class:`Prediction` at the photo's resolution (maps zero outside the mask)."""
        h, w = self.size
        return Prediction(albedo=paste_from_box(self.albedo, self.box, h, w).mul_(self.mask),
                          transport=paste_from_box(self.transport, self.box, h, w).mul_(self.mask),
                          light=self.light, mask=self.mask, evidence=self.evidence, light_head=self.light_head)


def frame_person(image: torch.Tensor, mask: torch.Tensor, size: int, pad: float = 0.05):
    """KE18 framing of a photo: (3, H, W) float image and (H, W) float mask cropped around the mask
    and resized to size² → (image (1, 3, s, s), binary mask (1, 1, s, s), :class:`CropBox`)."""
    box = mask_crop_box(mask, pad)
    s = (int(size), int(size))
    x = F.interpolate(crop_to_box(image[None], box), size=s, mode="bilinear", align_corners=False)
    m = F.interpolate(crop_to_box(mask[None, None], box), size=s, mode="bilinear", align_corners=False)
    return x, (m > 0.5).float(), box


def _check_predicted_mask(person: torch.Tensor) -> None:
    """Warn when a mask-head mask looks like the background: most of the frame and the top edge.

    The mask head learned from synthetic people only; on real photos it can swap person and
    background (scikit-image's ``astronaut``: 73% of the frame and 95% of the top edge).
    """
    cover, top = float(person.float().mean()), float(person[0].float().mean())
    if cover > 0.6 and top > 0.5:
        logger.warning("the mask head's person covers %.0f%% of the image and %.0f%% of its top edge: it may have "
                       "taken the background for the person (it learned from synthetic people); give a mask",
                       100 * cover, 100 * top)


#: A predicted person covering more of the frame than this is no person found (a mask of everything).
MAX_PERSON_COVER = 0.99
#: An image whose values span less than this (any channel, sRGB in [0, 1]) is blank: one colour.
BLANK_RANGE = 2 / 255


def check_not_blank(image: torch.Tensor, name: str = "image") -> None:
    """Refuse a blank image (black, white, one colour) before looking for a person in it.

    Args:
        image: (3, H, W) sRGB in [0, 1].

    Raises:
        InputError: its values span less than :data:`BLANK_RANGE`.
    """
    check_shape(image, [3, "H", "W"], name=name)
    span = float(image.amax() - image.amin())
    if span < BLANK_RANGE:
        raise InputError(f"{name}: blank (a single colour, values spanning {span:.4f}): there is no person to "
                         "find; expected a photo of a person, or give the person's mask")


def check_predicted_person(mask: torch.Tensor, name: str = "image") -> None:
    """Refuse a mask-head result that found no person: empty, or (nearly) the whole frame.

    Args:
        mask: (H, W) bool or {0, 1} predicted person mask.

    Raises:
        InputError: no person pixel, or more than :data:`MAX_PERSON_COVER` of the frame.
    """
    check_shape(mask, ["H", "W"], name="mask")
    cover = float((mask > 0.5).float().mean())
    if cover == 0:
        raise InputError(f"{name}: the mask head found no person in the image; give the person's mask")
    if cover > MAX_PERSON_COVER:
        raise InputError(f"{name}: the mask head marked {100 * cover:.1f}% of the frame as the person, which is "
                         "no person found (a mask of everything); give the person's mask")


def _network_input(model: RelightNet, image: torch.Tensor, mask: torch.Tensor | None, size: int | None,
                   pad: float) -> tuple[torch.Tensor, CropBox, torch.Tensor]:
    """(normalised network input (1, 4, s, s), crop box, mask (H, W)) of a photo (see predict_image)."""
    check_shape(image, [3, "H", "W"], name="image")
    if image.dtype == torch.uint8:
        image = image.float() / 255
    h, w = image.shape[-2:]
    m = model.config.multiple
    size = model.config.input_size if size is None else int(size)
    if size % m:
        raise InputError(f"size: expected a multiple of {m}, got {size}")
    dev = next(model.parameters()).device
    image = image.to(dev)
    if mask is None:
        if not model.config.mask_head:
            raise InputError("mask: this model has no mask head; give a mask of the person")
        check_not_blank(image)
        full = CropBox((h - max(h, w)) // 2, (w - max(h, w)) // 2, max(h, w))
        x = F.interpolate(crop_to_box(image[None], full), size=(size, size), mode="bilinear", align_corners=False)
        coarse = model(normalize_input(x, torch.ones_like(x[:, :1])))
        mask = paste_from_box(coarse.mask, full, h, w)[0, 0]
        check_predicted_person(mask)
        _check_predicted_mask(mask > 0.5)
    check_shape(mask, [h, w], name="mask")
    mask = mask.to(dev).float()
    x, mk, box = frame_person(image, mask, size, pad)
    return normalize_input(x, mk), box, mask


@torch.no_grad()
def predict_crop(model: RelightNet, image: torch.Tensor, mask: torch.Tensor | None = None,
                 size: int | None = None, pad: float = 0.05) -> CropMaps:
    """:func:`predict_image` without the paste: the maps at the working size (:class:`CropMaps`)."""
    x, box, mask = _network_input(model, image, mask, size, pad)
    pred = model(x)
    return CropMaps(pred.albedo, pred.transport, pred.light, mask[None, None], box, pred.evidence, pred.light_head)


@torch.no_grad()
def predict_image(model: RelightNet, image: torch.Tensor, mask: torch.Tensor | None = None,
                  size: int | None = None, pad: float = 0.05) -> tuple[Prediction, CropBox | None]:
    """Predict albedo, transport, light (and mask) for one photo at its own resolution.

    Args:
        model: a :class:`RelightNet` (eval mode).
        image: (3, H, W) sRGB in [0, 1] (or uint8).
        mask: (H, W) person mask in [0, 1]; None uses the model's mask head on the whole
            frame (padded to a square) and then crops around the predicted mask.
        size: working resolution (a multiple of the model's 2**levels); default: the size the
            model was trained at (``model.config.input_size``, from its checkpoint).
        pad: crop padding (fraction of the mask box's larger side).

    Returns:
        (prediction at the original resolution with a batch of 1 — maps are zero outside the
        crop, ``mask`` is the given or predicted mask — and the crop box used).
    """
    crop = predict_crop(model, image, mask, size, pad)
    return crop.pasted(), crop.box


@torch.no_grad()
def estimate_light(model: RelightNet, image: torch.Tensor, mask: torch.Tensor | None = None,
                   size: int | None = None, pad: float = 0.05) -> torch.Tensor:
    """The SH light (K, 3) of a photo, camera-relative light frame, linear RGB.

    Same arguments as :func:`predict_image`; the maps are not pasted back (cheaper).
    """
    x, _, _ = _network_input(model, image, mask, size, pad)
    return model(x).light[0]


@torch.no_grad()
def estimate_light_evidence(model: RelightNet, image: torch.Tensor, mask: torch.Tensor | None = None,
                            size: int | None = None, pad: float = 0.05):
    """The light of a photo with what a video needs to pool it over a shot.

    Same arguments as :func:`predict_image`.

    Returns:
        ``(light (K, 3), evidence, prior)``: the solve's :class:`~relightnet.sh.light_solve.Evidence`
        (``M`` (1, 3, K, K), ``r`` (1, 3, K)) and its prior light (K, 3) — None for a network that
        regresses its light (``light_mode="head"``), and the prior None for ``"solve"``.
    """
    x, _, _ = _network_input(model, image, mask, size, pad)
    p = model(x)
    return p.light[0], p.evidence, None if p.light_head is None else p.light_head[0]
