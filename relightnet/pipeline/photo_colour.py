"""Does relighting invent colour? Two figures of a photo relit under white side lights (``evaluate photos``).

A white light changes the person's shading, not their colour: the relit person's chromaticity
should differ from the photo's by the photo light's own tint only (a few hundredths). Where the
photo albedo divides by a weak or wrongly coloured predicted shading, green and magenta blotches
appear instead. Both figures compare the relit photo with the photo, on the person:

- the photo (and the relit one) shrunk to :data:`COLOUR_HEIGHT` px high when taller (area average),
  the person its mask > 0.5 eroded by :data:`ERODE_PX` px (:func:`relightnet.raster.erode`);
- linear RGB, chromaticity (r, g) = (R, G) / (R + G + B) (:func:`chromaticity`);
- **chroma shift**: |Δr| + |Δg| per pixel between the relit photo and the photo, its 99th percentile
  over the person;
- **fine-scale chroma energy ratio**: the chromaticity minus its Gaussian blur (σ = :data:`FINE_SIGMA`
  px), its mean square over the person, relit ÷ photo (1: no colour noise added).

The lights are :data:`COLOUR_LIGHTS` (in words, :func:`relightnet.light.light_from_words`): a white key
light from the left and one from the right, with a little ambient.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from ..checks import InputError, check_shape
from ..color import srgb_to_linear
from ..data.backgrounds import gaussian_blur
from ..raster.morphology import erode

__all__ = ["COLOUR_LIGHTS", "COLOUR_HEIGHT", "ERODE_PX", "FINE_SIGMA", "chromaticity", "colour_figures"]

#: The white side lights of the colour figures, in words.
COLOUR_LIGHTS = {"white_left": "key:az=-70,el=10,power=3 + ambient:0.15",
                 "white_right": "key:az=70,el=10,power=3 + ambient:0.15"}
#: Photos taller than this are shrunk to it for the colour figures.
COLOUR_HEIGHT = 768
#: The person's mask is eroded by this many pixels (at :data:`COLOUR_HEIGHT`).
ERODE_PX = 3
#: Standard deviation (px) of the blur that separates fine-scale chroma.
FINE_SIGMA = 3.0


def chromaticity(linear: torch.Tensor, eps: float = 1e-6) -> torch.Tensor:
    """(3, H, W) linear RGB → (2, H, W) chromaticity (R, G) / (R + G + B) (a black pixel: 1/3, 1/3)."""
    check_shape(linear, [3, "H", "W"], name="image")
    x = linear.clamp_min(0)
    total = x.sum(0, keepdim=True)
    return torch.where(total > eps, x[:2] / total.clamp_min(eps), torch.full_like(x[:2], 1 / 3))


def _shrink(x: torch.Tensor, height: int) -> torch.Tensor:
    h, w = x.shape[-2:]
    if h <= height:
        return x
    return F.interpolate(x[None], size=(height, max(1, round(w * height / h))), mode="area")[0]


def _fine_energy(chroma: torch.Tensor, person: torch.Tensor) -> float:
    fine = chroma - gaussian_blur(chroma.permute(1, 2, 0), FINE_SIGMA).permute(2, 0, 1)
    return float((fine.square().sum(0) * person).sum() / person.sum())


def colour_figures(photo: torch.Tensor, relit: torch.Tensor, mask: torch.Tensor,
                   height: int = COLOUR_HEIGHT) -> dict:
    """Chroma shift p99 and fine-scale chroma energy ratio of ``relit`` against ``photo`` (module docstring).

    Args:
        photo, relit: (3, H, W) sRGB in [0, 1].
        mask: (H, W) the person where > 0.5.
        height: photos taller than this are shrunk to it first.

    Returns:
        ``{"chroma_shift_p99", "fine_chroma_ratio"}`` (floats).

    Raises:
        InputError: no person pixel left after the erosion.
    """
    dims = check_shape(photo, [3, "H", "W"], name="photo")
    check_shape(relit, [3, dims["H"], dims["W"]], name="relit")
    check_shape(mask, [dims["H"], dims["W"]], name="mask")
    stack = _shrink(torch.cat([photo.double(), relit.double(), mask.double()[None]]), height)
    person = erode((stack[6:] > 0.5).double()[None], ERODE_PX)[0, 0]
    if not bool(person.any()):
        raise InputError(f"mask: no person pixel left after eroding it by {ERODE_PX} px")
    c_photo = chromaticity(srgb_to_linear(stack[:3].clamp(0, 1)))
    c_relit = chromaticity(srgb_to_linear(stack[3:6].clamp(0, 1)))
    shift = (c_relit - c_photo).abs().sum(0)[person > 0]
    base = _fine_energy(c_photo, person)
    ratio = _fine_energy(c_relit, person) / base if base > 0 else float("nan")
    return {"chroma_shift_p99": float(torch.quantile(shift, 0.99)), "fine_chroma_ratio": ratio}
