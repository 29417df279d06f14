"""How far an estimated SH light is from the truth, as the shading it causes.

All measures compare irradiance ``E(d) = Σ_k Â_l L_k Y_k(d)`` on a shared set of uniform
directions (4,096 Fibonacci points, or the camera-facing half of them):

- :func:`scale_invariant_light_error`: relative error ``min_s ‖s E_est − E_true‖ / ‖E_true‖`` over
  all directions and the three channels at once (one scale for RGB: colour errors count,
  exposure does not) — over the sphere it is exact in coefficient space (the SH basis is
  orthonormal: the irradiance inner product is Σ_k Â_l² a_k b_k) and differentiable (a
  training loss); over the camera-facing hemisphere it is sampled;
- :func:`dominant_direction` / :func:`direction_error`: the direction of the luminance's
  l = 1 vector (where the light mostly comes from) and the angle between two of them;
- :func:`chromaticity_error`: distance between the (r, g) chromaticities of the mean
  irradiance (the light's overall colour).
"""

from __future__ import annotations

import math

import torch

from ..checks import check_shape
from ..color import luminance
from .basis import sh_basis
from .directions import fibonacci_sphere
from .irradiance import cosine_lobe_per_coeff

__all__ = ["METRIC_DIRECTIONS", "irradiance_samples", "scale_invariant_light_error", "dominant_direction",
           "direction_error", "chromaticity_error"]

#: Directions the irradiance is compared on.
METRIC_DIRECTIONS = 4096


def irradiance_samples(sh: torch.Tensor, hemisphere: bool = False) -> torch.Tensor:
    """Irradiance of lights on the metric's direction set.

    Args:
        sh: (..., K, 3) lights (light frame).
        hemisphere: only the directions facing the camera (x_light > 0).

    Returns:
        (..., D, 3) float64, D = 4,096 (or about half with ``hemisphere``).
    """
    check_shape(sh, ["...", "K", 3], name="light")
    k = sh.shape[-2]
    lmax = math.isqrt(k) - 1
    d = fibonacci_sphere(METRIC_DIRECTIONS, dtype=torch.float64, device=sh.device)[0]
    if hemisphere:
        d = d[d[:, 0] > 0]
    basis = sh_basis(d, lmax, check=False) * cosine_lobe_per_coeff(lmax, dtype=torch.float64, device=sh.device)
    return basis @ sh.double()


def scale_invariant_light_error(est: torch.Tensor, truth: torch.Tensor, hemisphere: bool = False) -> torch.Tensor:
    """Scale-invariant relative irradiance error ``min_s ‖s E_est − E_true‖ / ‖E_true‖``.

    Args:
        est, truth: (..., K, 3) lights (broadcastable).
        hemisphere: compare on the camera-facing directions only (sampled, float64); else over the
            whole sphere, exactly, in the inputs' dtype (differentiable).

    Returns:
        (...) error in [0, 1] (1: no better than a zero light).
    """
    if hemisphere:
        a, b = irradiance_samples(est, True), irradiance_samples(truth, True)
        dims, w = (-2, -1), 1.0
    else:
        check_shape(est, ["...", "K", 3], name="est")
        a, b, dims = est, truth.to(est.dtype), (-2, -1)
        lmax = math.isqrt(est.shape[-2]) - 1
        w = cosine_lobe_per_coeff(lmax, dtype=est.dtype, device=est.device)[:, None] ** 2
    ab, aa, bb = (a * b * w).sum(dims), (a * a * w).sum(dims), (b * b * w).sum(dims)
    cos2 = ab.square() / (aa * bb).clamp_min(1e-30)
    return (1 - cos2).clamp_min(1e-12).sqrt()


def dominant_direction(sh: torch.Tensor) -> torch.Tensor:
    """(..., K, 3) light → (..., 3) unit vector (light frame) of its luminance's l = 1 band.

    The l = 1 coefficients (k = 1, 2, 3) are proportional to (y, z, x) of the mean direction
    the light comes from.
    """
    check_shape(sh, ["...", "K", 3], name="light")
    lum = luminance(sh.double())  # (..., K)
    v = torch.stack([lum[..., 3], lum[..., 1], lum[..., 2]], -1)
    return v / v.norm(dim=-1, keepdim=True).clamp_min(1e-30)


def direction_error(est: torch.Tensor, truth: torch.Tensor) -> torch.Tensor:
    """(...) angle in degrees between the dominant directions of two (..., K, 3) lights."""
    c = (dominant_direction(est) * dominant_direction(truth)).sum(-1).clamp(-1, 1)
    return torch.rad2deg(torch.acos(c))


def chromaticity_error(est: torch.Tensor, truth: torch.Tensor) -> torch.Tensor:
    """(...) L2 distance of the (r, g) chromaticities of the lights' mean irradiance (DC terms)."""
    def rg(sh):
        dc = sh.double()[..., 0, :].clamp_min(1e-12)
        return (dc / dc.sum(-1, keepdim=True))[..., :2]

    return (rg(est) - rg(truth)).norm(dim=-1)
