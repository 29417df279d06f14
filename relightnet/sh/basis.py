"""Real orthonormal spherical harmonics of any order.

Convention (docs/design.md, "Spherical harmonics"): real, orthonormal, no Condon–Shortley phase, flat index
``k = l(l+1) + m``. Directions are unit vectors in the *light frame*
(x toward the camera, y image right, z up). For order 2:

====  =====================  ====  ==========================
k     Y_k                    k     Y_k
====  =====================  ====  ==========================
0     0.282095               5     1.092548·yz
1     0.488603·y             6     0.315392·(3z²−1)
2     0.488603·z             7     1.092548·xz
3     0.488603·x             8     0.546274·(x²−y²)
4     1.092548·xy
====  =====================  ====  ==========================

Evaluation is polynomial in (x, y, z): with ``C_m + i S_m = (x + i y)^m`` and
the associated Legendre polynomials divided by ``sin^m θ`` (``Q_l^m(z)``, a
stable three-term recurrence in l), ``Y_l^{±m} = √2 N_l^m Q_l^m(z) {C_m, S_m}``.
No trigonometry, differentiable everywhere, exact at the poles.
"""

from __future__ import annotations

import math

import torch
from torch import nn

from ..checks import check_shape, check_unit

__all__ = ["sh_count", "sh_index", "sh_degrees", "sh_basis", "SHBasis"]


def sh_count(lmax: int) -> int:
    """Number of coefficients K = (lmax+1)² up to order ``lmax``.

    Example:
        >>> from relightnet.sh import sh_count
        >>> sh_count(2), sh_count(4)
        (9, 25)
    """
    if int(lmax) != lmax or lmax < 0:
        raise ValueError(f"lmax: expected a non-negative integer, got {lmax!r}")
    return (int(lmax) + 1) ** 2


def sh_index(l: int, m: int) -> int:
    """Flat index k = l(l+1)+m of the coefficient (l, m), |m| ≤ l.

    Example:
        >>> from relightnet.sh import sh_index
        >>> sh_index(0, 0), sh_index(1, -1), sh_index(2, 2)
        (0, 1, 8)
    """
    if l < 0 or abs(m) > l:
        raise ValueError(f"(l, m): expected l >= 0 and |m| <= l, got ({l}, {m})")
    return l * (l + 1) + m


def sh_degrees(lmax: int, device=None) -> torch.Tensor:
    """(K,) int64 tensor giving the band l of every flat index k.

    Example:
        >>> from relightnet.sh.basis import sh_degrees
        >>> sh_degrees(2).tolist()
        [0, 1, 1, 1, 2, 2, 2, 2, 2]
    """
    return torch.tensor([l for l in range(lmax + 1) for _ in range(2 * l + 1)], device=device)


def _norm(l: int, m: int) -> float:
    """N_l^m = sqrt((2l+1)/(4π) · (l−m)!/(l+m)!), times √2 for m ≠ 0."""
    n = math.sqrt((2 * l + 1) / (4 * math.pi) * math.exp(math.lgamma(l - m + 1) - math.lgamma(l + m + 1)))
    return n * math.sqrt(2.0) if m else n


def sh_basis(dirs: torch.Tensor, lmax: int, check: bool = True) -> torch.Tensor:
    """Evaluate all real SH up to ``lmax`` at unit directions.

    Args:
        dirs: (..., 3) unit directions in the light frame, float32 or float64.
        lmax: maximum order l (K = (lmax+1)² outputs).
        check: validate shape and unit length (turn off in hot loops whose
            directions are known to be unit).

    Returns:
        (..., K) basis values, same dtype and device as ``dirs``.

    Example:
        The basis straight up (z, the light frame's up) is Y_0 = 0.282095 and Y_2 = 0.488603
        (docs/design.md, "Spherical harmonics"):

        >>> import torch
        >>> from relightnet.sh import sh_basis
        >>> Y = sh_basis(torch.tensor([[0.0, 0.0, 1.0]]), lmax=2)
        >>> Y.shape
        torch.Size([1, 9])
        >>> [round(v, 6) for v in Y[0, :3].tolist()]
        [0.282095, 0.0, 0.488603]
    """
    sh_count(lmax)
    if check:
        check_shape(dirs, ["...", 3], name="dirs")
        check_unit(dirs, name="dirs")
    if not dirs.is_floating_point():
        raise TypeError(f"dirs: expected a floating dtype, got {dirs.dtype}")
    if lmax > 24 and dirs.dtype != torch.float64:
        # (2m−1)!! passes float32's range at m = 29: evaluate high orders in float64.
        return sh_basis(dirs.double(), lmax, check=False).to(dirs.dtype)
    x, y, z = dirs.unbind(-1)
    out: list[torch.Tensor | float] = [0.0] * sh_count(lmax)
    # C_m, S_m: real and imaginary parts of (x + i y)^m (C_0 = 1, S_0 = 0).
    cs: list[tuple] = [(1.0, 0.0), (x, y)]
    for _ in range(2, lmax + 1):
        c, s = cs[-1]
        cs.append((c * x - s * y, s * x + c * y))
    for m in range(lmax + 1):
        # Q_l^m(z) for l = m..lmax: Q_m^m = (2m-1)!! (a constant), Q_{m+1}^m = (2m+1) z Q_m^m,
        # (l-m) Q_l^m = (2l-1) z Q_{l-1}^m - (l+m-1) Q_{l-2}^m.
        q_prev2: torch.Tensor | float = 0.0
        q_prev: torch.Tensor | float = float(math.prod(range(1, 2 * m, 2)))
        for l in range(m, lmax + 1):
            if l == m:
                q = q_prev
            else:
                q = ((2 * l - 1) * q_prev) * z
                if l > m + 1:
                    q = (q - (l + m - 1) * q_prev2) / (l - m)
                q_prev2, q_prev = q_prev, q
            n = _norm(l, m)
            if m == 0:
                out[sh_index(l, 0)] = n * q
            else:
                c, s = cs[m]
                out[sh_index(l, m)] = (n * q) * c
                out[sh_index(l, -m)] = (n * q) * s
    # Constant entries (l = 0 and the m = l = 1 band's scalar factors) become full tensors.
    cols = [o if isinstance(o, torch.Tensor) else torch.full_like(x, o) for o in out]
    return torch.stack(cols, dim=-1)


class SHBasis(nn.Module):
    """Module form of :func:`sh_basis`: ``(..., 3) -> (..., K)``.

    Example:
        >>> import torch
        >>> from relightnet.sh import SHBasis
        >>> SHBasis(lmax=3)(torch.tensor([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])).shape
        torch.Size([2, 16])
    """

    def __init__(self, lmax: int = 2, check: bool = True) -> None:
        super().__init__()
        self.lmax, self.check = lmax, check

    def forward(self, dirs: torch.Tensor) -> torch.Tensor:
        return sh_basis(dirs, self.lmax, self.check)
