"""Augmentations that keep a sample physically consistent: pixel = albedo ⊙ (T · L).

Samples are dicts of tensors in the CNN layout (what :class:`relightnet.data.SynthDataset`
returns): spatial fields are (C, H, W) — or (T, C, H, W) for clips — and ``light`` is
(K, 3) (or (T, K, 3)). Every function returns a new dict and leaves its input alone.

- :func:`hflip` mirrors left ↔ right. In the light frame (x toward the camera, y image
  right, z up) that is y → −y, which flips the sign of every SH function odd in y:
  exactly those with m < 0 (:func:`sh_mirror_signs`; order 2: k = 1, 4, 5). Transport
  channels and light rows take the same signs, so T · L is unchanged at the mirrored
  pixel; the y component of ``normals`` flips; part labels can be swapped left ↔ right.
- :func:`crop`, :func:`resize`: geometry only (nearest resampling keeps the identity
  exact; bilinear is smoother and holds it only approximately).
- :func:`scale_intensity`, :func:`white_balance`: scale the light (all or per colour
  channel) and every radiance field with it (``image``, ``background``; the 8-bit sRGB
  fields are re-encoded); albedo and transport do not change.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
import torch.nn.functional as F

from ..checks import InputError
from ..color import linear_to_srgb, srgb_to_linear

__all__ = [
    "SPATIAL_FIELDS",
    "RADIANCE_FIELDS",
    "sh_mirror_signs",
    "mirror_directions",
    "mirror_label_map",
    "hflip",
    "crop",
    "resize",
    "scale_intensity",
    "white_balance",
    "Augment",
]

#: Fields laid out (..., C, H, W) that geometric augmentations move.
SPATIAL_FIELDS = (
    "image", "image_srgb", "mask", "albedo", "transport", "transport_unoccluded", "normals", "depth",
    "parts", "background", "image_composite",
)
#: Linear radiance fields that photometric augmentations scale with the light.
RADIANCE_FIELDS = ("image", "background")
_SRGB_FIELDS = ("image_srgb", "image_composite")
_SH_FIELDS = ("transport", "transport_unoccluded")
_LABEL_FIELDS = ("parts", "mask")


def sh_mirror_signs(n_coeffs: int, dtype=torch.float32) -> torch.Tensor:
    """(K,) signs of the SH functions under the mirror y → −y: −1 where m < 0, else +1."""
    lmax = math.isqrt(int(n_coeffs)) - 1
    if (lmax + 1) ** 2 != n_coeffs or n_coeffs < 1:
        raise InputError(f"n_coeffs: expected a square (lmax+1)², got {n_coeffs}")
    return torch.tensor([-1.0 if m < 0 else 1.0 for l in range(lmax + 1) for m in range(-l, l + 1)], dtype=dtype)


def mirror_directions(dirs: torch.Tensor) -> torch.Tensor:
    """(..., 3) light-frame directions mirrored left ↔ right (y → −y)."""
    return dirs * dirs.new_tensor([1.0, -1.0, 1.0])


def _mirror_name(name: str) -> str:
    for a, b in ((".L", ".R"), (".R", ".L"), ("_l", "_r"), ("_r", "_l")):
        if name.endswith(a):
            return name[: -len(a)] + b
    for a, b in (("left", "right"), ("right", "left")):
        if a in name:
            return name.replace(a, b)
    return name


def mirror_label_map(names: Sequence[str]) -> torch.Tensor:
    """(n,) int64 map from each part label to its mirror image (``.L`` ↔ ``.R``, ``left`` ↔ ``right``)."""
    names = list(names)
    return torch.tensor([names.index(m) if (m := _mirror_name(n)) in names else i for i, n in enumerate(names)],
                        dtype=torch.int64)


def _check_sample(sample: dict) -> None:
    if not isinstance(sample, dict):
        raise InputError(f"sample: expected a dict of tensors, got {type(sample).__name__}")


def hflip(sample: dict, label_map: torch.Tensor | None = None) -> dict:
    """Mirror a sample left ↔ right, consistently for SH transport, light and normals.

    Args:
        sample: {field: tensor}; spatial fields (..., C, H, W), ``light`` (..., K, 3).
        label_map: optional (n_labels,) map applied to ``parts`` (see :func:`mirror_label_map`).

    Returns:
        The mirrored sample: images flipped along W; ``transport*`` channels and ``light``
        rows times :func:`sh_mirror_signs`; ``normals`` y component negated.
    """
    _check_sample(sample)
    out = dict(sample)
    for name, x in sample.items():
        if name in SPATIAL_FIELDS:
            x = x.flip(-1)
            if name in _SH_FIELDS:
                x = x * sh_mirror_signs(x.shape[-3], x.dtype)[:, None, None]
            elif name == "normals":
                x = x * x.new_tensor([1.0, -1.0, 1.0])[:, None, None]
            elif name == "parts" and label_map is not None:
                x = label_map.to(x.device)[x.long()].to(x.dtype)
            out[name] = x
        elif name == "light":
            out[name] = x * sh_mirror_signs(x.shape[-2], x.dtype)[:, None]
    return out


def crop(sample: dict, top: int, left: int, height: int, width: int) -> dict:
    """Crop every spatial field to rows ``top:top+height``, columns ``left:left+width``."""
    _check_sample(sample)
    out = dict(sample)
    for name, x in sample.items():
        if name in SPATIAL_FIELDS:
            h, w = x.shape[-2:]
            if not (0 <= top and 0 <= left and height >= 1 and width >= 1 and top + height <= h
                    and left + width <= w):
                raise InputError(f"crop: box (top={top}, left={left}, {height}x{width}) is outside {name} {h}x{w}")
            out[name] = x[..., top:top + height, left:left + width]
    return out


def _nearest_index(n_in: int, n_out: int, device) -> torch.Tensor:
    return ((torch.arange(n_out, device=device, dtype=torch.float64) + 0.5) * (n_in / n_out)).long().clamp_(0, n_in - 1)


def resize(sample: dict, size: int | tuple[int, int], mode: str = "nearest") -> dict:
    """Resample every spatial field to ``size`` (an int for square, or (H, W)).

    ``mode="nearest"`` keeps pixel = albedo ⊙ (T·L) exact (each output pixel is one input
    pixel); ``"bilinear"`` (float fields only; masks/labels/uint8 stay nearest) is smoother
    and keeps the identity only approximately.
    """
    _check_sample(sample)
    if mode not in ("nearest", "bilinear"):
        raise InputError(f"mode: expected 'nearest' or 'bilinear', got {mode!r}")
    oh, ow = (size, size) if isinstance(size, int) else tuple(size)
    if oh < 1 or ow < 1:
        raise InputError(f"size: expected positive sizes, got {size!r}")
    out = dict(sample)
    for name, x in sample.items():
        if name not in SPATIAL_FIELDS:
            continue
        h, w = x.shape[-2:]
        if (h, w) == (oh, ow):
            continue
        if mode == "bilinear" and x.is_floating_point() and name not in _LABEL_FIELDS:
            lead = x.shape[:-2]
            y = F.interpolate(x.reshape(1, -1, h, w), size=(oh, ow), mode="bilinear", align_corners=False,
                              antialias=oh < h or ow < w)
            out[name] = y.reshape(*lead, oh, ow)
        else:
            rows, cols = _nearest_index(h, oh, x.device), _nearest_index(w, ow, x.device)
            out[name] = x[..., rows, :][..., cols]
    return out


def _color_scale(sample: dict, gains: torch.Tensor) -> dict:
    """Multiply the light's colour columns and every radiance field's channels by ``gains`` (3,)."""
    out = dict(sample)
    g3 = gains[:, None, None]
    for name, x in sample.items():
        if name == "light":
            out[name] = x * gains.to(x)
        elif name in RADIANCE_FIELDS:
            out[name] = x * g3.to(x)
        elif name in _SRGB_FIELDS:
            lin = srgb_to_linear(x.float() / 255.0) * g3.to(x.device)
            out[name] = (linear_to_srgb(lin).clamp(0, 1) * 255).round().to(x.dtype)
    return out


def scale_intensity(sample: dict, scale: float) -> dict:
    """Scale the light and every radiance field by ``scale`` > 0 (exposure change)."""
    _check_sample(sample)
    if not float(scale) > 0 or not math.isfinite(float(scale)):
        raise InputError(f"scale: expected a positive number, got {scale!r}")
    return _color_scale(sample, torch.full((3,), float(scale)))


def white_balance(sample: dict, gains) -> dict:
    """Scale the light's R, G, B columns and every radiance field's channels by ``gains`` (3,) > 0."""
    _check_sample(sample)
    gains = torch.as_tensor(gains, dtype=torch.float32).reshape(-1)
    if gains.shape != (3,) or not bool((gains > 0).all()) or not bool(torch.isfinite(gains).all()):
        raise InputError(f"gains: expected 3 positive numbers, got {gains.tolist()}")
    return _color_scale(sample, gains)


def _uniform(g: torch.Generator | None, lo: float, hi: float, n: int = 1) -> torch.Tensor:
    return lo + (hi - lo) * torch.rand(n, generator=g, dtype=torch.float64)


class Augment:
    """Random consistent augmentation: flip, crop (+ optional resize), intensity, white balance.

    Args:
        flip: probability of :func:`hflip`.
        crop_scale: (lo, hi) side of a random square crop as a fraction of the image side;
            ``None`` or (1, 1) for no crop.
        size: output side after the crop (resampled with ``mode``); ``None`` keeps the crop's
            own size (no resampling, exact).
        multiple: output sides are rounded down to a multiple of this (16 for the CNN); 1 for any.
        intensity: (lo, hi) range of a log-uniform exposure scale; ``None`` for none.
        white_balance: max |log gain| per colour channel (gains normalised to geometric mean 1).
        mode: resampling for ``size`` (``"nearest"`` or ``"bilinear"``).
        label_map: optional left ↔ right map of ``parts`` labels for flips.

    Call ``aug(sample, generator=None)``; the generator (or torch's global RNG) draws everything.
    """

    def __init__(self, flip: float = 0.5, crop_scale: tuple | None = (0.75, 1.0), size: int | None = None,
                 multiple: int = 16, intensity: tuple | None = (0.5, 2.0), white_balance: float = 0.1,
                 mode: str = "nearest", label_map: torch.Tensor | None = None) -> None:
        if not 0.0 <= flip <= 1.0:
            raise InputError(f"flip: expected a probability, got {flip}")
        if crop_scale is not None and not 0.0 < crop_scale[0] <= crop_scale[1] <= 1.0:
            raise InputError(f"crop_scale: expected 0 < lo <= hi <= 1, got {crop_scale}")
        if intensity is not None and not 0.0 < intensity[0] <= intensity[1]:
            raise InputError(f"intensity: expected 0 < lo <= hi, got {intensity}")
        if white_balance < 0 or multiple < 1 or (size is not None and size < multiple):
            raise InputError(f"white_balance >= 0, multiple >= 1, size >= multiple expected; got "
                             f"{white_balance}, {multiple}, {size}")
        self.flip, self.crop_scale, self.size, self.multiple = flip, crop_scale, size, int(multiple)
        self.intensity, self.wb, self.mode, self.label_map = intensity, float(white_balance), mode, label_map

    def __repr__(self) -> str:
        return (f"Augment(flip={self.flip}, crop_scale={self.crop_scale}, size={self.size}, multiple={self.multiple}, "
                f"intensity={self.intensity}, white_balance={self.wb}, mode={self.mode!r})")

    def _round(self, n: int) -> int:
        return max(self.multiple, n // self.multiple * self.multiple)

    def __call__(self, sample: dict, generator: torch.Generator | None = None) -> dict:
        g = generator
        h, w = sample["image"].shape[-2:] if "image" in sample else next(
            sample[k].shape[-2:] for k in sample if k in SPATIAL_FIELDS)
        if float(_uniform(g, 0, 1)) < self.flip:
            sample = hflip(sample, self.label_map)
        s = 1.0 if self.crop_scale is None else float(_uniform(g, *self.crop_scale))
        ch, cw = max(1, round(s * h)), max(1, round(s * w))
        if self.size is None:
            ch, cw = min(h, self._round(ch)), min(w, self._round(cw))
        top = int(_uniform(g, 0, 1) * (h - ch + 1)) if ch < h else 0
        left = int(_uniform(g, 0, 1) * (w - cw + 1)) if cw < w else 0
        if (ch, cw) != (h, w):
            sample = crop(sample, min(top, h - ch), min(left, w - cw), ch, cw)
        if self.size is not None:
            sample = resize(sample, self._round(self.size), self.mode)
        if self.intensity is not None:
            lo, hi = math.log(self.intensity[0]), math.log(self.intensity[1])
            sample = scale_intensity(sample, math.exp(float(_uniform(g, lo, hi))))
        if self.wb > 0:
            logg = _uniform(g, -self.wb, self.wb, 3)
            sample = white_balance(sample, torch.exp(logg - logg.mean()).float())
        return sample
