"""Texture sampling at per-pixel UV coordinates.

UV convention (OBJ / OpenGL): ``u`` runs left → right and ``v`` runs **bottom → top**
of the texture image, both in [0, 1]; ``(0, 0)`` is the bottom-left corner of the
image as stored (row ``Ht−1``), ``(0, 1)`` the top-left corner (row 0). Texel
``(row i, col j)`` has its centre at ``u = (j + 0.5) / Wt``, ``v = 1 − (i + 0.5) / Ht``.
"""

from __future__ import annotations

import torch

from ..checks import InputError, check_shape

__all__ = ["texture"]


def _wrap(i: torch.Tensor, n: int, mode: str) -> torch.Tensor:
    return torch.remainder(i, n) if mode == "repeat" else torch.clamp(i, 0, n - 1)


def texture(tex: torch.Tensor, uv: torch.Tensor, filter: str = "bilinear", wrap: str = "clamp",
            mask: torch.Tensor | None = None, check: bool = True) -> torch.Tensor:
    """Sample textures at UV coordinates.

    Args:
        tex: (B, C, Ht, Wt) textures, or (1, C, Ht, Wt) shared by the batch.
        uv: (B, H, W, 2) coordinates (module docstring: v = 0 at the bottom).
        filter: ``"bilinear"`` (between the four nearest texel centres) or ``"nearest"``.
        wrap: ``"clamp"`` (edge texels extend outward) or ``"repeat"`` (tiling; bilinear
            blends across the seam).
        mask: optional (B, H, W) bool; only these pixels are sampled, others are 0.
        check: validate the inputs.

    Returns:
        (B, H, W, C) samples, differentiable w.r.t. ``tex`` and (bilinear) ``uv``.
    """
    if check:
        check_shape(tex, ["Bt", "C", "Ht", "Wt"], name="tex")
        dims = check_shape(uv, ["B", "H", "W", 2], name="uv")
        if tex.shape[0] not in (1, dims["B"]):
            raise InputError(f"tex: batch {tex.shape[0]} must be 1 or match uv's batch {dims['B']}")
        if filter not in ("bilinear", "nearest"):
            raise InputError(f"filter: expected 'bilinear' or 'nearest', got {filter!r}")
        if wrap not in ("clamp", "repeat"):
            raise InputError(f"wrap: expected 'clamp' or 'repeat', got {wrap!r}")
        if mask is not None:
            check_shape(mask, ["B", "H", "W"], name="mask", dims=dims)
    B, H, W, _ = uv.shape
    Bt, C, Ht, Wt = tex.shape
    texels = tex.permute(0, 2, 3, 1).reshape(Bt * Ht * Wt, C)
    flat_uv = uv.reshape(B * H * W, 2)
    bidx = torch.arange(B, device=uv.device).repeat_interleave(H * W) if Bt > 1 else None
    pix = None
    if mask is not None:
        pix = torch.nonzero(mask.reshape(-1)).squeeze(1)
        flat_uv = flat_uv.index_select(0, pix)
        bidx = bidx.index_select(0, pix) if bidx is not None else None
    base = bidx * (Ht * Wt) if bidx is not None else 0
    x = flat_uv[:, 0] * Wt - 0.5  # texel-centre coordinates
    y = (1.0 - flat_uv[:, 1]) * Ht - 0.5
    if filter == "nearest":
        j = _wrap(torch.floor(x + 0.5).long(), Wt, wrap)
        i = _wrap(torch.floor(y + 0.5).long(), Ht, wrap)
        vals = texels.index_select(0, base + i * Wt + j)
    else:
        x0, y0 = torch.floor(x), torch.floor(y)
        fx, fy = (x - x0)[:, None].to(tex.dtype), (y - y0)[:, None].to(tex.dtype)
        j0, i0 = x0.long(), y0.long()
        j = (_wrap(j0, Wt, wrap), _wrap(j0 + 1, Wt, wrap))
        i = (_wrap(i0, Ht, wrap) * Wt + base, _wrap(i0 + 1, Ht, wrap) * Wt + base)
        top = torch.lerp(texels.index_select(0, i[0] + j[0]), texels.index_select(0, i[0] + j[1]), fx)
        bot = torch.lerp(texels.index_select(0, i[1] + j[0]), texels.index_select(0, i[1] + j[1]), fx)
        vals = torch.lerp(top, bot, fy)
    if pix is not None:
        vals = torch.zeros(B * H * W, C, dtype=vals.dtype, device=vals.device).index_copy(0, pix, vals)
    return vals.view(B, H, W, C)
