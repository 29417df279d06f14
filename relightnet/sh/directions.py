"""Direction sets with quadrature weights, and the lat-long parameterisation.

A shared direction set turns SH projection into one matmul:
``coeffs = Yᵀ (w ⊙ f)`` with ``Y = sh_basis(dirs)`` computed once.

Lat-long (equirectangular) maps are indexed in the *world* frame (+y up):
row v ∈ [0, H) runs from straight up (top) to straight down, column u ∈ [0, W)
runs over azimuth with the image centre looking along −z (what the default
camera sees behind the subject) and u increasing toward +x:
``θ = π (v + ½)/H``, ``φ = 2π (u + ½)/W − π``,
``d = (sin θ sin φ, cos θ, −sin θ cos φ)``.
"""

from __future__ import annotations

import math

import torch

__all__ = [
    "fibonacci_sphere",
    "fibonacci_hemisphere",
    "random_fibonacci_sphere",
    "latlong_directions",
    "directions_to_latlong",
]

_GOLDEN = (1 + 5**0.5) / 2


def _fib(n: int, zmin: float, dtype, device) -> torch.Tensor:
    if int(n) != n or n < 1:
        raise ValueError(f"n: expected a positive integer number of directions, got {n!r}")
    i = torch.arange(n, dtype=torch.float64, device=device)
    z = 1 - (1 - zmin) * (i + 0.5) / n
    r = torch.sqrt((1 - z * z).clamp_min(0))
    phi = 2 * math.pi * i / _GOLDEN
    return torch.stack([r * torch.cos(phi), r * torch.sin(phi), z], -1).to(dtype)


def fibonacci_sphere(n: int, dtype=torch.float32, device=None) -> tuple[torch.Tensor, torch.Tensor]:
    """Near-uniform spherical Fibonacci lattice.

    Returns:
        dirs: (n, 3) unit directions; weights: (n,) equal solid angles, summing to 4π.
    """
    d = _fib(n, -1.0, dtype, device)
    return d, torch.full((n,), 4 * math.pi / n, dtype=dtype, device=device)


def fibonacci_hemisphere(n: int, dtype=torch.float32, device=None) -> tuple[torch.Tensor, torch.Tensor]:
    """Fibonacci lattice on the hemisphere z ≥ 0.

    Returns:
        dirs: (n, 3) unit directions with z > 0; weights: (n,) summing to 2π.
    """
    d = _fib(n, 0.0, dtype, device)
    return d, torch.full((n,), 2 * math.pi / n, dtype=dtype, device=device)


def random_fibonacci_sphere(
    n: int, generator: torch.Generator | None = None, dtype=torch.float32, device=None
) -> tuple[torch.Tensor, torch.Tensor]:
    """Randomised quasi-Monte-Carlo set: a Fibonacci lattice under a uniformly random rotation.

    Unbiased for any integrand, deterministic for a seeded ``generator``.

    Returns:
        dirs: (n, 3); weights: (n,) summing to 4π.
    """
    d, w = fibonacci_sphere(n, torch.float64, device)
    q = torch.randn(4, generator=generator, dtype=torch.float64).to(device)
    q = q / q.norm()
    a, b, c, e = q.tolist()
    R = torch.tensor(
        [
            [1 - 2 * (c * c + e * e), 2 * (b * c - a * e), 2 * (b * e + a * c)],
            [2 * (b * c + a * e), 1 - 2 * (b * b + e * e), 2 * (c * e - a * b)],
            [2 * (b * e - a * c), 2 * (c * e + a * b), 1 - 2 * (b * b + c * c)],
        ],
        dtype=torch.float64,
        device=device,
    )
    return (d @ R.T).to(dtype), w.to(dtype)


def latlong_directions(h: int, w: int, dtype=torch.float32, device=None) -> tuple[torch.Tensor, torch.Tensor]:
    """World directions and exact solid angles of lat-long pixel centres.

    Returns:
        dirs: (H, W, 3) world-frame unit directions; solid_angle: (H, W), summing to 4π.
    """
    if h < 1 or w < 1:
        raise ValueError(f"latlong size: expected H, W >= 1, got ({h}, {w})")
    v = torch.arange(h, dtype=torch.float64, device=device)
    u = torch.arange(w, dtype=torch.float64, device=device)
    theta = math.pi * (v + 0.5) / h
    phi = 2 * math.pi * (u + 0.5) / w - math.pi
    st, ct = torch.sin(theta)[:, None], torch.cos(theta)[:, None]
    d = torch.stack(
        [st * torch.sin(phi)[None], ct.expand(h, w), -st * torch.cos(phi)[None]], -1
    )
    edges = torch.cos(math.pi * torch.arange(h + 1, dtype=torch.float64, device=device) / h)
    sa = ((edges[:-1] - edges[1:]) * (2 * math.pi / w))[:, None].expand(h, w)
    return d.to(dtype), sa.to(dtype).contiguous()


def directions_to_latlong(dirs: torch.Tensor, h: int, w: int) -> torch.Tensor:
    """Continuous lat-long pixel coordinates (u, v) of world directions.

    Args:
        dirs: (..., 3) world-frame unit directions.

    Returns:
        (..., 2) pixel coordinates (u in [0, W), v in [0, H)), pixel centres at +0.5.
    """
    x, y, z = dirs.unbind(-1)
    theta = torch.acos(y.clamp(-1, 1))
    phi = torch.atan2(x, -z)
    return torch.stack([(phi + math.pi) / (2 * math.pi) * w, theta / math.pi * h], -1)
