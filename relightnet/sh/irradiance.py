"""Clamped-cosine convolution: Â_l and irradiance E(n) = Σ Â_l L_lm Y_lm(n); the same lobe restricted
to a cone of visibility (:func:`cone_transport`)."""

from __future__ import annotations

import math

import torch
from torch import nn

from ..checks import check_finite, check_sh_count, check_shape
from .basis import sh_basis, sh_degrees

__all__ = ["cosine_lobe", "cosine_lobe_per_coeff", "cone_band_factors", "cone_transport", "irradiance", "Irradiance"]


def cosine_lobe(l: int) -> float:
    """Â_l, the clamped-cosine convolution factor of band l.

    It is the factor with ``∫ max(n·ω, 0) Y_lm(ω) dω = Â_l Y_lm(n)``:
    Â_0 = π, Â_1 = 2π/3, odd l > 1 → 0, and for even l ≥ 2
    ``Â_l = 2π (−1)^{l/2−1} / ((l+2)(l−1)) · l! / (2^l ((l/2)!)²)``
    (Ramamoorthi & Hanrahan 2001, eq. 8). Â_2 = π/4.

    Example:
        >>> from relightnet.sh import cosine_lobe
        >>> [round(cosine_lobe(l), 4) for l in range(4)]  # π, 2π/3, π/4, 0
        [3.1416, 2.0944, 0.7854, 0.0]
    """
    if int(l) != l or l < 0:
        raise ValueError(f"l: expected a non-negative integer, got {l!r}")
    if l == 0:
        return math.pi
    if l == 1:
        return 2 * math.pi / 3
    if l % 2:
        return 0.0
    h = l // 2
    binom = math.exp(math.lgamma(l + 1) - l * math.log(2) - 2 * math.lgamma(h + 1))
    return 2 * math.pi * (-1) ** (h - 1) / ((l + 2) * (l - 1)) * binom


def cosine_lobe_per_coeff(lmax: int, dtype=torch.float32, device=None) -> torch.Tensor:
    """(K,) vector of Â_l repeated over each band's 2l+1 coefficients."""
    a = torch.tensor([cosine_lobe(l) for l in range(lmax + 1)], dtype=dtype, device=device)
    return a[sh_degrees(lmax, device=device)]


def _t_legendre_integrals(lmax: int) -> list[list[float]]:
    """Per band l, the coefficients c_j of ∫_c^1 t P_l(t) dt = Σ_j c_j (1 − c^(j+2)) (power series of P_l)."""
    import numpy as np
    from numpy.polynomial import legendre

    out = []
    for l in range(lmax + 1):
        p = legendre.leg2poly(np.eye(l + 1)[l])  # P_l's power-series coefficients, low degree first
        out.append([float(a) / (j + 2) for j, a in enumerate(p)])
    return out


def cone_band_factors(cos_aperture: torch.Tensor, lmax: int) -> torch.Tensor:
    """Band factors g_l(c) of the clamped cosine seen through a cone of half-angle α = acos(c) about its axis.

    The visibility of a point modelled as a cone around an axis b (a "bent normal") with the cosine
    taken about b: ``∫_{ω·b ≥ c} (ω·b) Y_lm(ω) dω = g_l(c) Y_lm(b)`` with
    ``g_l(c) = 2π ∫_c^1 t P_l(t) dt`` (the function is zonal about b: Funk–Hecke). ``c = 0`` (an open
    hemisphere) gives :func:`cosine_lobe`: g = (π, 2π/3, π/4, ...); ``c → 1`` (fully occluded) gives 0.
    Polynomial in c, so differentiable everywhere.

    Args:
        cos_aperture: (...) c in [0, 1] (values outside are clamped).
        lmax: SH order.

    Returns:
        (..., lmax + 1) g_l(c).
    """
    c = cos_aperture.clamp(0.0, 1.0)
    bands = []
    for coeffs in _t_legendre_integrals(lmax):
        g = torch.zeros_like(c)
        for j, a in enumerate(coeffs):
            if a:
                g = g + a * (1 - c ** (j + 2))
        bands.append(2 * math.pi * g)
    return torch.stack(bands, -1)


def cone_transport(axis: torch.Tensor, cos_aperture: torch.Tensor, lmax: int, check: bool = True) -> torch.Tensor:
    """SH transport of a point whose unoccluded directions form a cone: ``T_k = g_l(c) Y_k(b)``.

    The closed form of ``∫ V(ω) max(b·ω, 0) Y_k(ω) dω`` (docs/design.md's transport, no 1/π) when V is
    the indicator of the cone ``ω·b ≥ c`` and the cosine is taken about the cone's axis b
    (:func:`cone_band_factors`). With c = 0 it is the unoccluded transport Â_l Y_k(n).

    Args:
        axis: (..., 3) unit cone axes (bent normals) in the light frame.
        cos_aperture: (...) cosines of the cones' half-angles, in [0, 1].
        lmax: SH order.
        check: validate that ``axis`` holds unit vectors.

    Returns:
        (..., K) transport, K = (lmax + 1)².

    Example:
        A full hemisphere (c = 0) is the unoccluded transport Â_l Y_k(n); a narrower cone lets less light in:

        >>> import torch
        >>> from relightnet.sh import cone_transport, sh_basis
        >>> from relightnet.sh.irradiance import cosine_lobe_per_coeff
        >>> up = torch.tensor([[0.0, 0.0, 1.0]])
        >>> T = cone_transport(up, torch.tensor([0.0]), lmax=2)
        >>> T.shape, torch.allclose(T, cosine_lobe_per_coeff(2) * sh_basis(up, 2), atol=1e-6)
        (torch.Size([1, 9]), True)
        >>> bool(cone_transport(up, torch.tensor([0.5]), lmax=2)[0, 0] < T[0, 0])
        True
    """
    check_shape(cos_aperture, list(axis.shape[:-1]), name="cos_aperture")
    Y = sh_basis(axis, lmax, check=check)
    g = cone_band_factors(cos_aperture.to(Y.dtype), lmax)
    return Y * g[..., sh_degrees(lmax, device=Y.device)]


def irradiance(sh: torch.Tensor, normals: torch.Tensor, check: bool = True) -> torch.Tensor:
    """Irradiance from an SH light at given normals (no 1/π: white albedo radiance is E/π).

    Args:
        sh: (K, 3) light, linear RGB, light frame; or (B, K, 3) with normals (B, ..., 3).
        normals: (..., 3) unit normals in the light frame.
        check: validate inputs.

    Returns:
        (..., 3) irradiance E(n) = Σ_k Â_l(k) L_k Y_k(n).

    Example:
        Radiance 1 from every direction gives the irradiance π at any normal:

        >>> import math, torch
        >>> from relightnet.sh import irradiance
        >>> sh = torch.zeros(9, 3)
        >>> sh[0] = math.sqrt(4 * math.pi)
        >>> E = irradiance(sh, torch.tensor([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]]))
        >>> E.shape, round(E[1, 0].item(), 4)
        (torch.Size([2, 3]), 3.1416)
    """
    if check:
        check_shape(sh, ["...", "K", 3], name="sh")
        check_finite(sh, "sh")
    lmax = check_sh_count(sh, "sh")
    Y = sh_basis(normals, lmax, check=check)
    a = cosine_lobe_per_coeff(lmax, dtype=sh.dtype, device=sh.device)
    L = sh * a[:, None]
    if sh.dim() == 2:
        return Y @ L
    if sh.dim() != 3 or normals.shape[0] != sh.shape[0]:
        raise ValueError(
            f"sh: a batched light (B, K, 3) needs normals (B, ..., 3); got {tuple(sh.shape)} and {tuple(normals.shape)}"
        )
    b = sh.shape[0]
    return (Y.reshape(b, -1, Y.shape[-1]) @ L).reshape(*normals.shape[:-1], 3)


class Irradiance(nn.Module):
    """Module form of :func:`irradiance` holding a fixed light buffer (K, 3).

    Example:
        >>> import torch
        >>> from relightnet.sh import Irradiance
        >>> Irradiance(torch.zeros(9, 3))(torch.tensor([[1.0, 0.0, 0.0]])).shape
        torch.Size([1, 3])
    """

    def __init__(self, sh: torch.Tensor) -> None:
        super().__init__()
        self.register_buffer("sh", sh)

    def forward(self, normals: torch.Tensor) -> torch.Tensor:
        return irradiance(self.sh, normals)
