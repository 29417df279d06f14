"""Shading and compositing: the ``shade`` and ``composite`` primitives of both paths.

pixel = albedo ⊙ S with S = Σ_k T_k L_k per RGB channel (docs/design.md, "Transport and shading"),
all linear. These are the only kernels for T·L (:func:`shading`), A ⊙ (T·L) (:func:`shade`)
and alpha compositing (:func:`composite`) in relightnet: the CNN's maps, the 3D renderer and
every job use them.

Rasterizer outputs are channels-last, so these functions take (..., C) tensors; the CNN's
maps are channels-first (B, C, H, W). :func:`to_channels_last` and :func:`to_channels_first`
are the one named pair that converts (views, no copy).
"""

from __future__ import annotations

import torch
from torch import nn

from ..checks import check_finite, check_sh_count, check_shape

__all__ = ["shading", "shade", "composite", "composite_covered", "Shade"]

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
    if not per_channel and transport.dim() >= 3 and transport.stride(-1) != 1:
        # A channels-last view of channels-first memory (the CNN's maps, to_channels_last):
        # Sᵀ = Lᵀ Tᵀ in that memory layout, so the long pixel axis stays contiguous.
        if light.dim() == 3 and transport.shape[0] != light.shape[0]:
            raise ValueError(f"transport: a batched light (B={light.shape[0]}, K, 3) needs transport with leading "
                             f"dim B, got {tuple(transport.shape)}")
        t = transport.reshape(transport.shape[0], -1, k).transpose(1, 2)  # (B, K, N)
        return torch.matmul(light.transpose(-1, -2), t).transpose(1, 2).reshape(*transport.shape[:-1], 3)
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
    if per_channel:
        lb = light.reshape(b, *([1] * (transport.dim() - 3)), k, 3)
        return (transport * lb).sum(-2)
    # One (N, K) @ (K, 3) product per batch item (the leading dims after B are flattened; for a
    # channels-last view of a CNN map this is a view too).
    return torch.bmm(transport.reshape(b, -1, k), light).reshape(*transport.shape[:-1], 3)


def shade(albedo: torch.Tensor, transport: torch.Tensor, light: torch.Tensor, check: bool = True,
          with_shading: bool = False):
    """Lambertian PRT shading: albedo ⊙ (T · L).

    Args:
        albedo: (..., 3) linear RGB (e.g. (B, H, W, 3) or (V, 3)).
        transport: (..., K) or per-channel (..., K, 3), same leading dims as ``albedo``.
        light: (K, 3) or (B, K, 3) linear RGB SH light in the light frame.
        check: validate values (NaN/Inf in the light).
        with_shading: also return the shading S = T · L.

    Returns:
        (..., 3) linear radiance; with ``with_shading``, ``(radiance, S)`` both (..., 3).
    """
    if check:
        check_shape(albedo, ["...", 3], name="albedo")
        check_finite(light, "light")
    s = shading(transport, light)
    if with_shading:
        return albedo * s, s
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


def composite_covered(fg: torch.Tensor, pix: torch.Tensor, bg: torch.Tensor) -> torch.Tensor:
    """:func:`composite` for a binary coverage given as the covered pixels: they take ``fg``, every
    other pixel keeps ``bg`` (which is not modified), without touching the uncovered pixels.

    Args:
        fg: (N, C) the covered pixels' values (any dtype, e.g. 8-bit).
        pix: (N,) int64 flat indices into H·W (a rasterizer's ``Fragments.pix`` for one image).
        bg: (H, W, C).

    Returns:
        (H, W, C) of ``bg``'s dtype.
    """
    check_shape(bg, ["H", "W", "C"], name="bg")
    check_shape(fg, [pix.shape[0], bg.shape[-1]], name="fg")
    out = bg.clone()
    out.view(-1, bg.shape[-1]).index_copy_(0, pix, fg.to(out.dtype))
    return out


class Shade(nn.Module):
    """Module form of :func:`shade` with a fixed light buffer (K, 3)."""

    def __init__(self, light: torch.Tensor) -> None:
        super().__init__()
        self.register_buffer("light", light)

    def forward(self, albedo: torch.Tensor, transport: torch.Tensor) -> torch.Tensor:
        return shade(albedo, transport, self.light)
