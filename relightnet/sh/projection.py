"""Projection of spherical functions onto SH, and reconstruction.

Environment maps are lat-long images in the world frame (see
:mod:`relightnet.sh.directions`); SH coefficients are in the light frame.
"""

from __future__ import annotations

import torch

from ..checks import InputError, check_finite, check_sh_count, check_shape
from .basis import sh_basis, sh_index
from .directions import latlong_directions
from .frames import world_to_light

__all__ = ["project", "project_envmap", "radiance", "sh_to_envmap"]


def project(values: torch.Tensor, basis: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """Project sampled values on a shared direction set: one matmul.

    Args:
        values: (..., D, C) function values at the D directions.
        basis: (D, K) ``sh_basis`` of those directions.
        weights: (D,) quadrature weights (solid angles).

    Returns:
        (..., K, C) coefficients ``Σ_d w_d Y_k(d) f(d)``.

    Example:
        Projecting the constant 1 over a direction set recovers Y_0's coefficient √(4π) = 3.545:

        >>> import torch
        >>> from relightnet.sh import sh_basis, project
        >>> from relightnet.sh.directions import fibonacci_sphere
        >>> dirs, weights = fibonacci_sphere(4096)
        >>> coeffs = project(torch.ones(4096, 1), sh_basis(dirs, 2), weights)
        >>> coeffs.shape, round(coeffs[0, 0].item(), 3)
        (torch.Size([9, 1]), 3.545)
    """
    check_shape(basis, ["D", "K"], name="basis")
    check_shape(weights, ["D"], name="weights", dims={"D": basis.shape[0]})
    check_shape(values, ["...", "D", "C"], name="values", dims={"D": basis.shape[0]})
    return (basis * weights[:, None]).T @ values


def project_envmap(env: torch.Tensor, lmax: int = 2) -> torch.Tensor:
    """Project a lat-long environment map (world frame) to SH in the light frame.

    Args:
        env: (H, W, 3) linear radiance; negative values are clamped to 0.
        lmax: SH order.

    Returns:
        (K, 3) coefficients, dtype of ``env`` (float64 accumulation).

    Example:
        A uniform white sky has (up to the grid's quadrature) only the constant coefficient, √(4π) per channel:

        >>> import torch
        >>> from relightnet.sh import project_envmap
        >>> sh = project_envmap(torch.ones(32, 64, 3), lmax=2)
        >>> sh.shape
        torch.Size([9, 3])
        >>> round(sh[0, 0].item(), 3), bool(sh[1:].abs().max() < 0.01)
        (3.545, True)
    """
    check_shape(env, ["H", "W", 3], name="env")
    if not env.is_floating_point():
        raise InputError(f"env: expected a floating-point radiance map, got {env.dtype}")
    check_finite(env, "env")
    h, w = env.shape[:2]
    P, Phi, sa = _latlong_separable_basis(h, w, lmax, env.device)
    # Σ_w Φ_k(ψ_w) env[h, w, c]: one batched matmul over rows, then Σ_h P_k(θ_h) Ω_h.
    rows = env.clamp_min(0).to(torch.float64).transpose(1, 2) @ Phi  # (H, 3, K)
    return torch.einsum("hck,hk->kc", rows, P * sa[:, None]).to(env.dtype)


def _latlong_separable_basis(h: int, w: int, lmax: int, device) -> tuple[torch.Tensor, ...]:
    """Factor the SH basis over a lat-long grid: Y_k(θ_i, ψ_j) = P_k(θ_i) Φ_k(ψ_j).

    The lat-long poles are the world up axis, which is z_light, so θ is the light
    frame's polar angle and the light-frame azimuth is ψ = π − φ (see
    :mod:`relightnet.sh.directions`). ``P`` is the basis on the meridian ψ = 0
    (for m < 0 the same Legendre factor as +|m|), ``Φ`` is 1, cos(mψ) or sin(|m|ψ).

    Returns:
        P: (H, K), Phi: (W, K), solid angle per pixel of each row: (H,). float64.
    """
    f64 = torch.float64
    theta = torch.pi * (torch.arange(h, dtype=f64, device=device) + 0.5) / h
    meridian = torch.stack([torch.sin(theta), torch.zeros_like(theta), torch.cos(theta)], -1)
    P = sh_basis(meridian, lmax, check=False)
    psi = torch.pi - (2 * torch.pi * (torch.arange(w, dtype=f64, device=device) + 0.5) / w - torch.pi)
    Phi = torch.empty(w, P.shape[1], dtype=f64, device=device)
    for l in range(lmax + 1):
        for m in range(-l, l + 1):
            k = sh_index(l, m)
            if m < 0:
                P[:, k] = P[:, sh_index(l, -m)]
            Phi[:, k] = 1.0 if m == 0 else torch.cos(m * psi) if m > 0 else torch.sin(-m * psi)
    edges = torch.cos(torch.pi * torch.arange(h + 1, dtype=f64, device=device) / h)
    sa = (edges[:-1] - edges[1:]) * (2 * torch.pi / w)
    return P, Phi, sa


def radiance(sh: torch.Tensor, dirs: torch.Tensor, check: bool = True) -> torch.Tensor:
    """Radiance of an SH light in given directions.

    Args:
        sh: (K, 3) light (light frame).
        dirs: (..., 3) unit directions in the light frame.

    Returns:
        (..., 3) ``Σ_k L_k Y_k(d)``.

    Example:
        >>> import math, torch
        >>> from relightnet.sh import radiance
        >>> sh = torch.zeros(9, 3)
        >>> sh[0] = math.sqrt(4 * math.pi)  # radiance 1 from every direction
        >>> radiance(sh, torch.tensor([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])).round(decimals=4).tolist()
        [[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]]
    """
    if check:
        check_shape(sh, ["K", 3], name="sh")
        check_finite(sh, "sh")
    lmax = check_sh_count(sh, "sh")
    return sh_basis(dirs, lmax, check=check) @ sh


def sh_to_envmap(sh: torch.Tensor, h: int = 64, w: int | None = None) -> torch.Tensor:
    """Reconstruct a lat-long image (world frame) from SH coefficients, for viewing.

    Args:
        sh: (K, 3) light (light frame).
        h, w: output size (w defaults to 2h).

    Returns:
        (H, W, 3) radiance (may be negative where the band limit rings).

    Example:
        >>> import torch
        >>> from relightnet.sh import sh_to_envmap
        >>> sh_to_envmap(torch.zeros(9, 3), h=16).shape
        torch.Size([16, 32, 3])
    """
    w = 2 * h if w is None else w
    dirs, _ = latlong_directions(h, w, dtype=sh.dtype, device=sh.device)
    return radiance(sh, world_to_light(dirs), check=True)
