"""Clamped-cosine convolution: Â_l and irradiance E(n) = Σ Â_l L_lm Y_lm(n)."""

from __future__ import annotations

import math

import torch
from torch import nn

from ..checks import check_finite, check_sh_count, check_shape
from .basis import sh_basis, sh_degrees

__all__ = ["cosine_lobe", "cosine_lobe_per_coeff", "irradiance", "Irradiance"]


def cosine_lobe(l: int) -> float:
    """Â_l, the clamped-cosine convolution factor of band l.

    It is the factor with ``∫ max(n·ω, 0) Y_lm(ω) dω = Â_l Y_lm(n)``:
    Â_0 = π, Â_1 = 2π/3, odd l > 1 → 0, and for even l ≥ 2
    ``Â_l = 2π (−1)^{l/2−1} / ((l+2)(l−1)) · l! / (2^l ((l/2)!)²)``
    (Ramamoorthi & Hanrahan 2001, eq. 8). Â_2 = π/4.
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


def irradiance(sh: torch.Tensor, normals: torch.Tensor, check: bool = True) -> torch.Tensor:
    """Irradiance from an SH light at given normals (no 1/π: white albedo radiance is E/π).

    Args:
        sh: (K, 3) light, linear RGB, light frame; or (B, K, 3) with normals (B, ..., 3).
        normals: (..., 3) unit normals in the light frame.
        check: validate inputs.

    Returns:
        (..., 3) irradiance E(n) = Σ_k Â_l(k) L_k Y_k(n).
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
    """Module form of :func:`irradiance` holding a fixed light buffer (K, 3)."""

    def __init__(self, sh: torch.Tensor) -> None:
        super().__init__()
        self.register_buffer("sh", sh)

    def forward(self, normals: torch.Tensor) -> torch.Tensor:
        return irradiance(self.sh, normals)
