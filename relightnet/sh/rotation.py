"""Rotation of SH coefficients, any order.

For a rotation R (acting on light-frame directions), the rotated light is
``f'(ω) = f(Rᵀ ω)``. Rotations do not mix bands, so on a direction set D whose
basis matrix ``Y(D)`` has full column rank, ``Y(D) c' = Y(Rᵀ D) c`` holds
exactly and ``M(R) = pinv(Y(D)) Y(Rᵀ D)`` is the (K, K) block-diagonal rotation
matrix. ``D`` is a fixed Fibonacci set of 2K directions (well conditioned); the
solve is done in float64 and off-band entries are zeroed.
"""

from __future__ import annotations

import torch
from torch import nn

from ..checks import check_finite, check_sh_count, check_shape
from .basis import sh_basis, sh_count, sh_degrees
from .directions import fibonacci_sphere

__all__ = ["sh_rotation_matrix", "rotate_sh", "rotation_about_up", "rotate_sh_up", "RotateSH"]


def sh_rotation_matrix(R: torch.Tensor, lmax: int) -> torch.Tensor:
    """Block-diagonal SH rotation matrix.

    Args:
        R: (..., 3, 3) rotation matrices (light frame).
        lmax: SH order.

    Returns:
        (..., K, K) matrices M with ``rotated = M @ coeffs``, dtype of ``R``.

    Example:
        The matrix is block diagonal by band and orthogonal:

        >>> import torch
        >>> from relightnet.sh.rotation import rotation_about_up, sh_rotation_matrix
        >>> M = sh_rotation_matrix(rotation_about_up(0.3), lmax=2)
        >>> M.shape, torch.allclose(M @ M.T, torch.eye(9), atol=1e-5), M[0, 1:].abs().max().item() == 0
        (torch.Size([9, 9]), True, True)
    """
    check_shape(R, ["...", 3, 3], name="R")
    check_finite(R, "R")
    eye = torch.eye(3, dtype=torch.float64, device=R.device)
    R64 = R.to(torch.float64)
    err = (R64 @ R64.transpose(-1, -2) - eye).abs().amax().item() if R.numel() else 0.0
    if err > 1e-4 or (R.numel() and (torch.linalg.det(R64) < 0).any()):
        raise ValueError("R: expected proper rotation matrices (orthonormal, det +1)")
    k = sh_count(lmax)
    d, _ = fibonacci_sphere(max(2 * k, 8), dtype=torch.float64, device=R.device)
    pinv = torch.linalg.pinv(sh_basis(d, lmax, check=False))  # (K, D)
    # Rows of (Rᵀ d) are d @ R.
    Yr = sh_basis(d @ R64, lmax, check=False)  # (..., D, K)
    M = pinv @ Yr
    band = sh_degrees(lmax, device=R.device)
    M = M * (band[:, None] == band[None, :])
    return M.to(R.dtype)


def rotate_sh(sh: torch.Tensor, R: torch.Tensor) -> torch.Tensor:
    """Rotate SH lights.

    Args:
        sh: (..., K, 3) coefficients (light frame).
        R: (3, 3) rotation, or (..., 3, 3) broadcastable with ``sh``'s batch dims.

    Returns:
        (..., K, 3) coefficients of the light rotated by R.

    Example:
        A light along x (the camera) turned a quarter about the up axis lies along y (image right):

        >>> import math, torch
        >>> from relightnet.sh import rotate_sh
        >>> from relightnet.sh.rotation import rotation_about_up
        >>> sh = torch.zeros(9, 3)
        >>> sh[3] = 1.0  # k = 3: Y ∝ x
        >>> out = rotate_sh(sh, rotation_about_up(math.pi / 2))
        >>> [round(v, 4) + 0.0 for v in out[:4, 0].tolist()]  # k = 1: Y ∝ y
        [0.0, 1.0, 0.0, 0.0]
    """
    check_shape(sh, ["...", "K", 3], name="sh")
    lmax = check_sh_count(sh, "sh")
    M = sh_rotation_matrix(R, lmax).to(sh.dtype)
    return M @ sh


def rotation_about_up(angle: torch.Tensor | float, dtype=torch.float32, device=None) -> torch.Tensor:
    """Rotation about the up axis (z in the light frame, +y in the world), right-handed.

    Args:
        angle: radians, scalar or (N,) tensor.

    Returns:
        (3, 3) or (N, 3, 3) rotation matrices in the light frame.

    Example:
        >>> import math, torch
        >>> from relightnet.sh.rotation import rotation_about_up
        >>> (rotation_about_up(math.pi / 2).round() + 0.0).tolist()
        [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        >>> rotation_about_up(torch.zeros(4)).shape
        torch.Size([4, 3, 3])
    """
    a = torch.as_tensor(angle, dtype=dtype, device=device)
    c, s = torch.cos(a), torch.sin(a)
    o, z = torch.ones_like(a), torch.zeros_like(a)
    return torch.stack([c, -s, z, s, c, z, z, z, o], -1).reshape(*a.shape, 3, 3)


def rotate_sh_up(sh: torch.Tensor, angle: float) -> torch.Tensor:
    """Rotate (..., K, 3) lights by ``angle`` radians about the up axis.

    Example:
        The DC term (the light's mean) does not change under rotation:

        >>> import torch
        >>> from relightnet.sh import rotate_sh_up
        >>> sh = torch.randn(9, 3, generator=torch.Generator().manual_seed(0))
        >>> torch.allclose(rotate_sh_up(sh, 1.0)[0], sh[0], atol=1e-6)
        True
    """
    return rotate_sh(sh, rotation_about_up(angle, dtype=sh.dtype, device=sh.device))


class RotateSH(nn.Module):
    """Module form of :func:`rotate_sh` with a fixed rotation: (..., K, 3) -> (..., K, 3)."""

    def __init__(self, R: torch.Tensor, lmax: int = 2) -> None:
        super().__init__()
        self.register_buffer("M", sh_rotation_matrix(R, lmax))

    def forward(self, sh: torch.Tensor) -> torch.Tensor:
        check_shape(sh, ["...", self.M.shape[-1], 3], name="sh")
        return self.M @ sh


