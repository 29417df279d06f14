"""Distance between SH lights measured on the irradiance they produce, and outlier thresholds.

Two lights matter only through the diffuse shading they cause. For an SH light L
(K, 3) the irradiance is ``E(n) = Σ_k Â_l L_k Y_k(n)``; because the Y_k are
orthonormal over the sphere,

    ∫_S² ‖E_a(n) − E_b(n)‖² dn = Σ_k Σ_rgb Â_l(k)² (L_a − L_b)_k²,

a weighted L2 in coefficient space (weights π², (2π/3)², (π/4)², ... per band).
:func:`light_distance` is the square root of that integral (units: irradiance ·
sr^½); divide by √(4π) for the RMS irradiance error over directions.

Outlier thresholds (:func:`parse_eps`, :func:`outlier_threshold`) are either an
absolute distance or a robust multiple of the median absolute deviation of the
per-frame distances: ``"3mad"`` → ``median(d) + 3 · 1.4826 · MAD(d)``, MAD =
``median(|d − median(d)|)`` (1.4826 makes MAD a standard deviation for Gaussian data).
"""

from __future__ import annotations

import math
import re

import torch

from ..checks import InputError, check_sh_count, check_shape
from ..sh.irradiance import cosine_lobe_per_coeff

__all__ = [
    "light_weights", "light_distance", "light_norm", "parse_eps", "robust_scale", "outlier_threshold",
    "local_outlier_threshold",
]

_MAD_TO_SIGMA = 1.4826
_EPS_RE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*mad\s*$", re.IGNORECASE)


def light_weights(k: int, dtype=torch.float32, device=None) -> torch.Tensor:
    """(K,) weights Â_l(k)² of the irradiance metric for K = (lmax+1)² coefficients."""
    from ..checks import sh_order_from_count

    return cosine_lobe_per_coeff(sh_order_from_count(k), dtype=dtype, device=device) ** 2


def light_distance(
    a: torch.Tensor, b: torch.Tensor | None = None, squared: bool = False, weights: torch.Tensor | None = None
) -> torch.Tensor:
    """L2 distance between the irradiance of two lights over the whole sphere.

    Args:
        a: (..., K, 3) lights (linear RGB, light frame).
        b: (..., K, 3) lights broadcastable with ``a``; None means zero (gives the norm).
        squared: return ``∫ ‖E_a − E_b‖²`` instead of its square root.
        weights: (K,) :func:`light_weights`, when the caller has them (skips validation;
            for per-frame loops).

    Returns:
        (...) ``sqrt(Σ_k Σ_rgb Â_l² (a − b)_k²)``, summed over RGB. Differentiable
        (the square root gets a zero subgradient at 0).
    """
    diff = a if b is None else a - b
    if weights is None:
        check_shape(a, ["...", "K", 3], name="a")
        check_sh_count(a, "a")
        w = light_weights(a.shape[-2], dtype=diff.dtype, device=diff.device)
    else:
        w = weights.to(diff.dtype)
    sq = (diff.square() * w[:, None]).sum((-2, -1))
    if squared:
        return sq
    # sqrt with a finite gradient at exactly zero distance.
    return torch.where(sq > 0, sq.clamp_min(torch.finfo(sq.dtype).tiny).sqrt(), sq)


def light_norm(a: torch.Tensor, weights: torch.Tensor | None = None) -> torch.Tensor:
    """(...) irradiance L2 norm ``sqrt(∫ ‖E_a‖²)`` of lights (..., K, 3); ``weights`` as in :func:`light_distance`."""
    return light_distance(a, weights=weights)


def parse_eps(eps) -> tuple[str, float] | None:
    """Parse an outlier threshold.

    Args:
        eps: None / ``"none"`` (no outlier detection), a non-negative number or
            numeric string (absolute light distance), or ``"<c>mad"`` such as
            ``"3mad"`` (robust: c median absolute deviations above the median).

    Returns:
        None, ``("abs", value)`` or ``("mad", c)``.

    Raises:
        InputError: anything else, in one line.
    """
    if eps is None or (isinstance(eps, str) and eps.strip().lower() == "none"):
        return None
    if isinstance(eps, bool):
        raise InputError(f"outlier eps: expected a distance, 'none' or '<c>mad' (e.g. '3mad'), got {eps!r}")
    if isinstance(eps, (int, float)):
        value, kind = float(eps), "abs"
    elif isinstance(eps, str):
        m = _EPS_RE.match(eps)
        try:
            value, kind = (float(m.group(1)), "mad") if m else (float(eps), "abs")
        except ValueError:
            raise InputError(
                f"outlier eps: expected a distance, 'none' or '<c>mad' (e.g. '3mad'), got {eps!r}"
            ) from None
    else:
        raise InputError(f"outlier eps: expected a number or a string like '3mad', got {type(eps).__name__}")
    if not math.isfinite(value) or value < 0:
        raise InputError(f"outlier eps: expected a finite non-negative value, got {eps!r}")
    return kind, value


def robust_scale(d: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Median and MAD-based standard deviation along the last axis.

    Args:
        d: (..., T) values.

    Returns:
        ``(median (...), 1.4826 · MAD (...))``.
    """
    med = d.median(dim=-1).values
    mad = (d - med[..., None]).abs().median(dim=-1).values
    return med, _MAD_TO_SIGMA * mad


def outlier_threshold(d: torch.Tensor, eps, floor: float | torch.Tensor = 0.0) -> torch.Tensor:
    """Per-sequence distance above which a frame is an outlier.

    Args:
        d: (..., T) per-frame distances from a fit (:func:`light_distance`).
        eps: see :func:`parse_eps` (None gives +inf: nothing is an outlier).
        floor: lower bound of the threshold, scalar or (...): keeps exactly
            fitted data (all distances ~ rounding error) free of false outliers.

    Returns:
        (...) thresholds.
    """
    spec = parse_eps(eps)
    shape = d.shape[:-1]
    if spec is None:
        return torch.full(shape, math.inf, dtype=d.dtype, device=d.device)
    kind, value = spec
    if kind == "abs":
        thr = torch.full(shape, value, dtype=d.dtype, device=d.device)
    else:
        med, sigma = robust_scale(d)
        thr = med + value * sigma
    return torch.maximum(thr, torch.as_tensor(floor, dtype=d.dtype, device=d.device).expand(shape))


def local_outlier_threshold(d: torch.Tensor, eps, window: int | None = 61, floor=0.0) -> torch.Tensor:
    """Per-frame outlier thresholds from the distances of nearby frames.

    Like :func:`outlier_threshold`, but the median and MAD of ``"<c>mad"`` are taken
    over the ``window`` frames around each frame (shifted inward at the ends), so a
    noise level that changes along the sequence (a brighter light is estimated with
    larger errors) is followed. The threshold is never below the local median: at
    most about half the frames of any window are outliers.

    Args:
        d: (..., T) per-frame distances.
        eps: see :func:`parse_eps`.
        window: frames per local window; None or ≥ T: one window (the whole sequence).
        floor: lower bound, broadcastable to (..., T).

    Returns:
        (..., T) thresholds.
    """
    spec = parse_eps(eps)
    if spec is None:
        return torch.full_like(d, math.inf)
    n = d.shape[-1]
    w = n if window is None else max(1, min(int(window), n))
    t = torch.arange(n, device=d.device)
    idx = (t - w // 2).clamp(0, n - w)[:, None] + torch.arange(w, device=d.device)  # (T, w)
    win = d[..., idx]  # (..., T, w)
    med = win.median(dim=-1).values
    if spec[0] == "abs":
        thr = torch.full_like(d, spec[1])
    else:
        mad = (win - med[..., None]).abs().median(dim=-1).values
        thr = med + spec[1] * _MAD_TO_SIGMA * mad
    return torch.maximum(torch.maximum(thr, med), torch.as_tensor(floor, dtype=d.dtype, device=d.device))
