"""Texture sampling at per-pixel UV coordinates.

UV convention (OBJ / OpenGL): ``u`` runs left → right and ``v`` runs **bottom → top**
of the texture image, both in [0, 1]; ``(0, 0)`` is the bottom-left corner of the
image as stored (row ``Ht−1``), ``(0, 1)`` the top-left corner (row 0). Texel
``(row i, col j)`` has its centre at ``u = (j + 0.5) / Wt``, ``v = 1 − (i + 0.5) / Ht``.
"""

from __future__ import annotations

import torch

from ..checks import InputError, check_shape

__all__ = ["texture", "texture_pixels"]


def _wrap(i: torch.Tensor, n: int, mode: str) -> torch.Tensor:
    return torch.remainder(i, n) if mode == "repeat" else torch.clamp(i, 0, n - 1)


def _check_modes(filter: str, wrap: str) -> None:
    if filter not in ("bilinear", "nearest"):
        raise InputError(f"filter: expected 'bilinear' or 'nearest', got {filter!r}")
    if wrap not in ("clamp", "repeat"):
        raise InputError(f"wrap: expected 'clamp' or 'repeat', got {wrap!r}")


def _sample(tex: torch.Tensor, uv: torch.Tensor, base, filter: str, wrap: str) -> torch.Tensor:
    """(N, C) samples of ``tex`` (Bt, C, Ht, Wt) at ``uv`` (N, 2); ``base`` offsets each into its texture."""
    Bt, C, Ht, Wt = tex.shape
    texels = tex.permute(0, 2, 3, 1).reshape(Bt * Ht * Wt, C)
    x = uv[:, 0] * Wt - 0.5  # texel-centre coordinates
    y = (1.0 - uv[:, 1]) * Ht - 0.5
    if filter == "nearest":
        j = _wrap(torch.floor(x + 0.5).long(), Wt, wrap)
        i = _wrap(torch.floor(y + 0.5).long(), Ht, wrap)
        return texels.index_select(0, base + i * Wt + j)
    x0, y0 = torch.floor(x), torch.floor(y)
    fx, fy = (x - x0)[:, None].to(tex.dtype), (y - y0)[:, None].to(tex.dtype)
    j0, i0 = x0.long(), y0.long()
    j = (_wrap(j0, Wt, wrap), _wrap(j0 + 1, Wt, wrap))
    i = (_wrap(i0, Ht, wrap) * Wt + base, _wrap(i0 + 1, Ht, wrap) * Wt + base)
    top = torch.lerp(texels.index_select(0, i[0] + j[0]), texels.index_select(0, i[0] + j[1]), fx)
    bot = torch.lerp(texels.index_select(0, i[1] + j[0]), texels.index_select(0, i[1] + j[1]), fx)
    return torch.lerp(top, bot, fy)


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
        _check_modes(filter, wrap)
        if mask is not None:
            check_shape(mask, ["B", "H", "W"], name="mask", dims=dims)
    B, H, W, _ = uv.shape
    Bt, C, Ht, Wt = tex.shape
    flat_uv = uv.reshape(B * H * W, 2)
    bidx = torch.arange(B, device=uv.device).repeat_interleave(H * W) if Bt > 1 else None
    pix = None
    if mask is not None:
        pix = torch.nonzero(mask.reshape(-1)).squeeze(1)
        flat_uv = flat_uv.index_select(0, pix)
        bidx = bidx.index_select(0, pix) if bidx is not None else None
    vals = _sample(tex, flat_uv, bidx * (Ht * Wt) if bidx is not None else 0, filter, wrap)
    if pix is not None:
        vals = torch.zeros(B * H * W, C, dtype=vals.dtype, device=vals.device).index_copy(0, pix, vals)
    return vals.view(B, H, W, C)


def texture_pixels(tex: torch.Tensor, uv: torch.Tensor, batch: torch.Tensor | None = None,
                   filter: str = "bilinear", wrap: str = "clamp", check: bool = True) -> torch.Tensor:
    """Sample textures at the N covered pixels only (the compact form of :func:`texture`).

    Args:
        tex: (B, C, Ht, Wt) textures, or (1, C, Ht, Wt) shared by the batch.
        uv: (N, 2) coordinates, e.g. ``interpolate_pixels(uv, frags, uv_faces)``.
        batch: (N,) int64 batch element of each pixel (``Fragments.pix_batch``); needed when B > 1.
        filter, wrap, check: as in :func:`texture`.

    Returns:
        (N, C) samples, the values :func:`texture` gives at those pixels.
    """
    if check:
        dims = check_shape(uv, ["N", 2], name="uv")
        check_shape(tex, ["Bt", "C", "Ht", "Wt"], name="tex")
        if tex.shape[0] > 1:
            if batch is None:
                raise InputError(f"batch: needed to sample {tex.shape[0]} textures")
            check_shape(batch, [dims["N"]], name="batch")
            if batch.numel() and not 0 <= int(batch.min()) <= int(batch.max()) < tex.shape[0]:
                raise InputError(f"batch: expected indices in [0, {tex.shape[0]})")
        _check_modes(filter, wrap)
    Ht, Wt = tex.shape[-2:]
    base = batch * (Ht * Wt) if tex.shape[0] > 1 else 0
    return _sample(tex, uv, base, filter, wrap)
