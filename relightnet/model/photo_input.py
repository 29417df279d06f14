"""Training inputs made the way a user's photo reaches the network.

A generated item is a person rendered alone, already framed: every pixel inside its mask is
the person's own radiance, and the silhouette's last pixels show the grazing shading exactly.
A photo or a video frame is not like that: the person stands over a background that the
silhouette's pixels blend into, :func:`~relightnet.model.inference.frame_person` cuts a box
around a mask (the segmentation's, a pixel or two off) and resamples it to the working size,
and in a video the person may cover few pixels. A network trained on the renders alone learns
to read the light from those exact silhouette pixels: on the test items its light error is
0.17 through the renders, 0.47 through the same items' composites and 0.41 when the render is
only re-framed (BENCHMARKS.md, "The light of a photo").

:class:`PhotoInput` turns an item into what the package's own path gives the network: the
composite instead of the render (probability ``composite``), the item shrunk first
(``source_scale``: a person covering fewer pixels), the mask thresholded at that size, grown
or shrunk by up to ``mask_px`` pixels and, with probability ``mask_flaws``, given the flaws a
person segmentation has on real photos (:func:`mask_flaws`: holes, and slivers of background
stuck to the border), and :func:`~relightnet.model.inference.frame_person`
with a padding drawn from ``pad``. The targets (every spatial field) are resampled onto the
same box from the item's full resolution, so the losses compare like with like; the network
input goes in ``sample["input"]`` (4, S, S), which :func:`~relightnet.model.training.batch_to_input`
uses when present.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
import torch.nn.functional as F

from ..checks import InputError
from ..color import linear_to_srgb
from ..data.augment import SPATIAL_FIELDS, resize
from .inference import frame_person
from .network import normalize_input

__all__ = ["PhotoInput", "as_photo", "mask_flaws", "morph_mask", "photo_input"]

#: Most flaws per flawed mask, and their largest radius (a fraction of the mask box's larger side).
MAX_FLAWS, FLAW_RADIUS = 3, 0.08

#: Fields resampled as labels (then thresholded at 0.5), not as values.
_MASKS = ("mask",)


def morph_mask(mask: torch.Tensor, pixels: int) -> torch.Tensor:
    """Grow (``pixels`` > 0) or shrink (< 0) a binary mask by ``|pixels|`` pixels (square element).

    Args:
        mask: (H, W) in {0, 1}.

    Returns:
        (H, W) float in {0, 1}.
    """
    if pixels == 0:
        return mask.float()
    k = 2 * abs(int(pixels)) + 1
    m = mask.float()[None, None]
    out = F.max_pool2d(m, k, 1, k // 2) if pixels > 0 else -F.max_pool2d(-m, k, 1, k // 2)
    return out[0, 0]


def mask_flaws(mask: torch.Tensor, generator: torch.Generator) -> torch.Tensor:
    """A binary mask with the flaws of a person segmentation: 1 to :data:`MAX_FLAWS` disks, each
    either a hole (centred on a person pixel, removed) or a sliver of background (centred on a
    border pixel, added), of radius 1 px to :data:`FLAW_RADIUS` of the mask box's larger side.

    Args:
        mask: (H, W) in {0, 1}.
        generator: the draws' source (the same generator state gives the same flaws).

    Returns:
        (H, W) float in {0, 1}; the mask itself where a hole would have emptied it.
    """
    m = mask > 0.5
    ys, xs = torch.nonzero(m, as_tuple=True)
    if ys.numel() == 0:
        return mask.float()
    inner = -F.max_pool2d(-m.float()[None, None], 3, 1, 1)[0, 0] > 0.5
    by, bx = torch.nonzero(m & ~inner, as_tuple=True)  # border pixels (never empty when m is not)
    side = max(int(ys.max() - ys.min()), int(xs.max() - xs.min())) + 1
    h, w = m.shape
    yy, xx = torch.meshgrid(torch.arange(h), torch.arange(w), indexing="ij")
    out = m.clone()
    n = 1 + int(torch.randint(MAX_FLAWS, (1,), generator=generator))
    for u in torch.rand(n, 3, generator=generator, dtype=torch.float64).tolist():
        hole = u[0] < 0.5
        py, px = (ys, xs) if hole else (by, bx)
        i = min(int(u[1] * py.numel()), py.numel() - 1)
        r = 1.0 + u[2] * max(0.0, FLAW_RADIUS * side - 1.0)
        disk = (yy - int(py[i])) ** 2 + (xx - int(px[i])) ** 2 <= r * r
        out = out & ~disk if hole else out | disk
    return out.float() if bool(out.any()) else mask.float()


def _box_grid(box, scale: float, size: int, out: int, dtype) -> torch.Tensor:
    """(1, S, S, 2) ``grid_sample`` positions, in an item of ``size`` × ``size``, of the S × S
    (S = ``out``) output pixels of a :class:`~relightnet.model.inference.CropBox` drawn on the item
    shrunk to ``scale`` × its size."""
    i = (torch.arange(out, dtype=torch.float64) + 0.5) * (box.size / out)  # crop-continuous
    ys = ((box.top + i) / scale) * (2.0 / size) - 1.0
    xs = ((box.left + i) / scale) * (2.0 / size) - 1.0
    gy, gx = torch.meshgrid(ys, xs, indexing="ij")
    return torch.stack([gx, gy], -1)[None].to(dtype)


def as_photo(sample: dict, composite: bool, scale: float, mask_px: int, pad: float, size: int | None = None,
             flaws: int | None = None) -> dict:
    """One item framed as the package frames a photo (module docstring).

    Args:
        sample: a training item: ``image`` (3, H, W) linear (H = W), ``mask`` (1, H, W), the other
            spatial fields (C, H, W); ``image_composite`` (3, H, W) sRGB in [0, 255] when ``composite``.
        composite: the input is the composite (person over background) rather than the render.
        scale: the item is shrunk to ``scale`` × its size (≤ 1) before it is framed.
        mask_px: the mask at that size grown (> 0) or shrunk (< 0) by so many pixels.
        pad: the framing's padding (fraction of the mask box's larger side).
        size: the side S of the framed item (None: the item's own, H). An item made larger than
            the network's working size is framed *down* to it, as a photo is.
        flaws: a seed for :func:`mask_flaws` on the input's mask (None: none). The targets keep
            the exact mask: the network learns to see past the flaws.

    Returns:
        The item on the framed box at S × S: every spatial field resampled (``mask`` thresholded),
        ``input`` (4, S, S) the network input (:func:`~relightnet.model.normalize_input` of the
        framed photo and its framed mask).
    """
    h, w = sample["image"].shape[-2:]
    if h != w:
        raise InputError(f"as_photo: expected a square item, got {h}x{w}")
    if not 0.0 < scale <= 1.0:
        raise InputError(f"as_photo: scale must be in (0, 1], got {scale}")
    if composite and "image_composite" not in sample:
        raise InputError("as_photo: composite input asked for, but the item has no image_composite")
    srgb = sample["image_composite"] / 255.0 if composite else linear_to_srgb(sample["image"].clamp(0, 1))
    mask = sample["mask"][:1]
    hs = max(16, round(scale * h))
    if hs < h:
        srgb = F.interpolate(srgb[None], size=(hs, hs), mode="bilinear", align_corners=False, antialias=True)[0]
        mask = F.interpolate(mask[None], size=(hs, hs), mode="bilinear", align_corners=False, antialias=True)[0]
    seen = morph_mask(mask[0] > 0.5, mask_px)
    if not bool((seen > 0.5).any()):  # shrunk away: the thresholded mask as it is
        seen = (mask[0] > 0.5).float()
    if flaws is not None:
        seen = mask_flaws(seen, torch.Generator().manual_seed(flaws))
    if not bool((seen > 0.5).any()):
        raise InputError("as_photo: the item's mask is empty at the drawn scale")
    out_size = h if size is None else int(size)
    x, mk, box = frame_person(srgb.clamp(0, 1), seen, out_size, pad)
    grid = _box_grid(box, hs / h, h, out_size, sample["image"].dtype)
    out = dict(sample)
    for name, v in sample.items():
        if name not in SPATIAL_FIELDS or name == "image_composite":
            continue
        y = F.grid_sample(v[None].float(), grid, mode="bilinear", padding_mode="zeros", align_corners=False)[0]
        out[name] = (y > 0.5).to(v.dtype) if name in _MASKS else y.to(v.dtype)
    out.pop("image_composite", None)
    out["input"] = normalize_input(x, mk)[0]
    return out


@dataclass(frozen=True)
class PhotoInput:
    """Draws of :func:`as_photo` per item (``train`` config key ``photo``).

    Args:
        composite: probability that the input is the composite rather than the render.
        source_scale: (lo, hi) ⊂ (0, 1]: the item is shrunk to a log-uniform draw of this range.
        mask_px: the mask is grown or shrunk by a uniform draw of −mask_px … mask_px pixels.
        pad: (lo, hi) range of the framing's padding.
        prob: probability that an item is framed as a photo at all (else it stays the render).
        mask_flaws: probability that a photo-framed item's input mask gets :func:`mask_flaws`.
        size: the network's working size S when the items are larger (None: the items' own size).
            An item is then always framed down to S × S; one that is not drawn as a photo is its
            render framed the same way, unshrunk, its mask as it is.
    """

    composite: float = 0.5
    source_scale: tuple = (0.5, 1.0)
    mask_px: int = 1
    pad: tuple = (0.03, 0.08)
    prob: float = 1.0
    size: int | None = None
    mask_flaws: float = 0.0

    def __post_init__(self) -> None:
        lo, hi = (float(v) for v in self.source_scale)
        if not (0.0 <= self.composite <= 1.0 and 0.0 <= self.prob <= 1.0 and 0.0 <= self.mask_flaws <= 1.0):
            raise InputError(f"photo: composite, prob and mask_flaws are probabilities, got {self.composite}, "
                             f"{self.prob}, {self.mask_flaws}")
        if not 0.0 < lo <= hi <= 1.0:
            raise InputError(f"photo.source_scale: expected 0 < lo <= hi <= 1, got {list(self.source_scale)}")
        if isinstance(self.mask_px, bool) or not isinstance(self.mask_px, int) or not 0 <= self.mask_px <= 4:
            raise InputError(f"photo.mask_px: expected an integer in 0..4, got {self.mask_px!r}")
        if not 0.0 <= float(self.pad[0]) <= float(self.pad[1]) <= 0.5:
            raise InputError(f"photo.pad: expected 0 <= lo <= hi <= 0.5, got {list(self.pad)}")
        if self.size is not None and (isinstance(self.size, bool) or not isinstance(self.size, int)
                                      or self.size < 16 or self.size % 16):
            raise InputError(f"photo.size: expected a multiple of 16 (>= 16), got {self.size!r}")

    def __call__(self, sample: dict, generator: torch.Generator | None = None) -> dict:
        u = torch.rand(5, generator=generator, dtype=torch.float64).tolist()
        lo, hi = (math.log(float(v)) for v in self.source_scale)
        px = min(self.mask_px, int(u[3] * (2 * self.mask_px + 1)) - self.mask_px)
        pad = float(self.pad[0]) + u[4] * (float(self.pad[1]) - float(self.pad[0]))
        person = bool((sample["mask"] > 0.5).any())
        flaws = None
        if self.mask_flaws > 0:  # drawn only when asked: the other configs keep their random stream
            f = torch.rand(2, generator=generator, dtype=torch.float64).tolist()
            flaws = int(f[1] * 2**31) if f[0] < self.mask_flaws else None
        if u[0] < self.prob and person:
            try:
                return as_photo(sample, u[1] < self.composite and "image_composite" in sample,
                                math.exp(lo + u[2] * (hi - lo)), px, pad, self.size, flaws)
            except InputError:  # a sliver of a person that the shrinking lost: the render, as below
                pass
        if self.size is not None and self.size != sample["image"].shape[-1]:
            if person:
                return as_photo(sample, False, 1.0, 0, pad, self.size)
            sample = resize(sample, self.size, "bilinear")  # no person to frame: the whole item, resampled
        # the render as it is (every item of a batch carries an input)
        out = {k: v for k, v in sample.items() if k != "image_composite"}
        out["input"] = normalize_input(linear_to_srgb(sample["image"].clamp(0, 1))[None], sample["mask"][None])[0]
        return out

    def after(self, first):
        """This framing after another per-item transform ``first(sample, generator)`` (None: alone)."""
        if first is None:
            return self
        return lambda sample, generator=None: self(first(sample, generator), generator)


def photo_input(settings) -> PhotoInput | None:
    """The :class:`PhotoInput` of a training config's ``photo`` mapping (lists as tuples), or None
    for an empty one (the renders as they are).

    Raises:
        InputError: not a mapping, an unknown key or a value out of range.
    """
    if not isinstance(settings, dict):
        raise InputError(f"train config photo: expected a mapping, got {type(settings).__name__}")
    if not settings:
        return None
    unknown = set(settings) - set(PhotoInput.__dataclass_fields__)
    if unknown:
        raise InputError(f"train config photo: unknown keys {sorted(map(str, unknown))}")
    try:
        return PhotoInput(**{k: tuple(v) if isinstance(v, list) else v for k, v in settings.items()})
    except (TypeError, ValueError) as e:
        raise InputError(f"train config photo: a value has the wrong type ({str(e)[:160]})") from None
