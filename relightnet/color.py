"""Colour: the sRGB transfer functions and Rec. 709 luminance, in one place.

Every image inside relightnet is linear RGB; sRGB encoding happens only when 8-bit values are
read or written (docs/design.md, "Transport and shading"). The transfer functions are the exact
piecewise curves of IEC 61966-2-1. :func:`linear_to_srgb` / :func:`srgb_to_linear` work on
tensors (anything else is converted with ``torch.as_tensor``); :func:`srgb_to_linear_np` is the
same curve in float64 numpy, for the colour tables of the data generator (their values are
part of the generated data, so they are computed exactly as numpy computes them).
"""

from __future__ import annotations

import numpy as np
import torch

__all__ = ["LUMA", "linear_to_srgb", "srgb_to_linear", "srgb_to_linear_np", "luminance"]

#: Rec. 709 luminance weights of linear RGB.
LUMA = (0.2126, 0.7152, 0.0722)


def linear_to_srgb(x: torch.Tensor) -> torch.Tensor:
    """Exact piecewise sRGB encoding (IEC 61966-2-1) of linear values.

    ``12.92 x`` for ``x ≤ 0.0031308``, else ``1.055 x^(1/2.4) − 0.055``.

    Args:
        x: (...) linear values (not clamped; values above 1 stay above 1).

    Returns:
        (...) encoded values, same dtype.

    Example:
        >>> import torch
        >>> from relightnet.color import linear_to_srgb
        >>> [round(v, 4) for v in linear_to_srgb(torch.tensor([0.0, 0.002, 0.18, 1.0])).tolist()]
        [0.0, 0.0258, 0.4614, 1.0]
    """
    x = torch.as_tensor(x)
    hi = 1.055 * x.clamp_min(0.0031308) ** (1 / 2.4) - 0.055
    return torch.where(x <= 0.0031308, 12.92 * x, hi)


def srgb_to_linear(x: torch.Tensor) -> torch.Tensor:
    """Exact inverse of :func:`linear_to_srgb`.

    ``c / 12.92`` for ``c ≤ 0.04045``, else ``((c + 0.055)/1.055)^2.4``.

    Args:
        x: (...) sRGB-encoded values in [0, 1].

    Returns:
        (...) linear values, same dtype.

    Example:
        >>> import torch
        >>> from relightnet.color import linear_to_srgb, srgb_to_linear
        >>> x = torch.linspace(0, 1, 11, dtype=torch.float64)
        >>> torch.allclose(srgb_to_linear(linear_to_srgb(x)), x)
        True
    """
    x = torch.as_tensor(x)
    hi = ((x.clamp_min(0.04045) + 0.055) / 1.055) ** 2.4
    return torch.where(x <= 0.04045, x / 12.92, hi)


def srgb_to_linear_np(c, clip: bool = False) -> np.ndarray:
    """:func:`srgb_to_linear` in float64 numpy.

    Args:
        c: (...) sRGB values (array or numbers).
        clip: clip to [0, 1] first.

    Returns:
        (...) float64 linear values.
    """
    c = np.asarray(c, dtype=np.float64)
    if clip:
        c = np.clip(c, 0, 1)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def luminance(rgb):
    """(..., 3) linear RGB → (...) Rec. 709 luminance (:data:`LUMA`).

    A tensor gives a tensor of its dtype and device; anything else becomes a tensor first
    (``torch.as_tensor``).

    Example:
        >>> from relightnet.color import luminance
        >>> round(luminance([1.0, 1.0, 1.0]).item(), 4), round(luminance([0.0, 1.0, 0.0]).item(), 4)
        (1.0, 0.7152)
    """
    rgb = torch.as_tensor(rgb)
    return rgb @ torch.tensor(LUMA, dtype=rgb.dtype, device=rgb.device)
