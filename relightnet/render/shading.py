"""Shading and compositing: the ``shade`` primitive of the 3D (and 2D) path.

pixel = albedo ⊙ S with S = Σ_k T_k L_k per RGB channel (docs/design.md, "Transport and shading"), all linear.
Rasterizer outputs are channels-last, so these functions take (..., C) tensors.
"""

from __future__ import annotations

import torch
from torch import nn

from ..checks import check_finite, check_sh_count, check_shape

__all__ = ["shading", "shade", "composite", "Shade"]

#: Rows grouped per GEMM row in :func:`_project_rows` (see there).
_GROUP = 4


def _project_rows(t: torch.Tensor, light: torch.Tensor) -> torch.Tensor:
    """(N, K) @ (K, 3) at memory speed.

    A GEMM with 3 output columns runs far below the machine's bandwidth. Viewing
    G consecutive rows as one row of G·K values and multiplying by the
    block-diagonal ``I_G ⊗ L`` (G·K, 3G) yields the same (N, 3) result, laid out
    contiguously, with a GEMM shape BLAS handles well (G = 4 measured best here).
    """
    n, k = t.shape
    head = n - n % _GROUP
    out = torch.empty(n, 3, dtype=t.dtype, device=t.device)
    if head:
        lk = torch.block_diag(*([light] * _GROUP))
        torch.mm(t[:head].reshape(head // _GROUP, _GROUP * k), lk, out=out[:head].view(head // _GROUP, 3 * _GROUP))
    if head < n:
        torch.mm(t[head:], light, out=out[head:])
    return out


def shading(transport: torch.Tensor, light: torch.Tensor) -> torch.Tensor:
    """S = T · L.

    Args:
        transport: (..., K) per pixel or per vertex; for a per-channel transport
            (after coloured interreflection) (..., K, 3).
        light: (K, 3), or (B, K, 3) with ``transport`` (B, ..., K[, 3]).

    Returns:
        (..., 3) shading in linear RGB.
    """
    check_shape(light, ["...", "K", 3], name="light")
    k = light.shape[-2]
    check_sh_count(light, "light")
    per_channel = transport.dim() >= 2 and transport.shape[-1] == 3 and transport.shape[-2] == k
    if not per_channel:
        check_shape(transport, ["...", k], name="transport")
    light = light.to(transport.dtype)
    if light.dim() == 2:
        if per_channel:
            return (transport * light).sum(-2)
        if transport.is_contiguous() and not (transport.requires_grad or light.requires_grad):
            return _project_rows(transport.reshape(-1, k), light).reshape(*transport.shape[:-1], 3)
        return transport @ light
    b = light.shape[0]
    if transport.shape[0] != b:
        raise ValueError(
            f"transport: a batched light (B={b}, K, 3) needs transport with leading dim B, got {tuple(transport.shape)}"
        )
    lb = light.reshape(b, *([1] * (transport.dim() - (3 if per_channel else 2))), k, 3)
    if per_channel:
        return (transport * lb).sum(-2)
    return (transport.unsqueeze(-2) @ lb).squeeze(-2)


def shade(albedo: torch.Tensor, transport: torch.Tensor, light: torch.Tensor, check: bool = True) -> torch.Tensor:
    """Lambertian PRT shading: albedo ⊙ (T · L).

    Args:
        albedo: (..., 3) linear RGB (e.g. (B, H, W, 3) or (V, 3)).
        transport: (..., K) or per-channel (..., K, 3), same leading dims as ``albedo``.
        light: (K, 3) or (B, K, 3) linear RGB SH light in the light frame.
        check: validate values (NaN/Inf in the light).

    Returns:
        (..., 3) linear radiance.
    """
    if check:
        check_shape(albedo, ["...", 3], name="albedo")
        check_finite(light, "light")
    s = shading(transport, light)
    if s.requires_grad or albedo.requires_grad or s.shape != albedo.shape:
        return albedo * s
    return s.mul_(albedo)


def composite(fg: torch.Tensor, alpha: torch.Tensor, bg: torch.Tensor) -> torch.Tensor:
    """Alpha-composite a rendered foreground over a background: fg·α + bg·(1−α).

    Args:
        fg: (B, H, W, C) foreground (already multiplied by nothing: straight colour).
        alpha: (B, H, W) or (B, H, W, 1) coverage in [0, 1].
        bg: (B, H, W, C) or (H, W, C) background.

    Returns:
        (B, H, W, C).
    """
    check_shape(fg, ["B", "H", "W", "C"], name="fg")
    if alpha.dim() == 3:
        alpha = alpha.unsqueeze(-1)
    check_shape(alpha, [fg.shape[0], fg.shape[1], fg.shape[2], 1], name="alpha")
    check_shape(bg, ["...", fg.shape[1], fg.shape[2], fg.shape[3]], name="bg")
    alpha = alpha.to(fg.dtype)
    return torch.lerp(bg.to(fg.dtype).expand_as(fg), fg, alpha)


class Shade(nn.Module):
    """Module form of :func:`shade` with a fixed light buffer (K, 3)."""

    def __init__(self, light: torch.Tensor) -> None:
        super().__init__()
        self.register_buffer("light", light)

    def forward(self, albedo: torch.Tensor, transport: torch.Tensor) -> torch.Tensor:
        return shade(albedo, transport, self.light)
