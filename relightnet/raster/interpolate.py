"""Barycentric interpolation of vertex attributes over rasterized pixels."""

from __future__ import annotations

import torch
from torch import nn

from ..checks import InputError, ShapeError, check_shape
from .fragments import Fragments

__all__ = ["interpolate", "interpolate_pixels", "Interpolate", "to_channels_first", "to_channels_last"]


def interpolate_pixels(attr: torch.Tensor, frags: Fragments, faces: torch.Tensor,
                       check: bool = True) -> torch.Tensor:
    """Interpolated attributes at the covered pixels only (compact form).

    Args:
        attr: (V, C) attributes shared by the batch, or (B, V, C) per batch element.
        frags: :class:`Fragments` from :func:`relightnet.raster.rasterize`.
        faces: (F, 3) the faces that were rasterized.
        check: validate shapes.

    Returns:
        (N, C) values at ``frags.pix``; differentiable w.r.t. ``attr``.
    """
    B = frags.batch_size
    if check:
        if attr.dim() == 2:
            check_shape(attr, ["V", "C"], name="attr")
        elif attr.dim() == 3:
            check_shape(attr, [B, "V", "C"], name="attr")
        else:
            raise ShapeError(f"attr: expected (V, C) or (B={B}, V, C), got {tuple(attr.shape)}")
        check_shape(faces, ["F", 3], name="faces")
        if not attr.dtype.is_floating_point:
            raise InputError(f"attr: expected a floating tensor, got {attr.dtype}")
    V, C = attr.shape[-2:]
    f = faces.to(device=attr.device, dtype=torch.long)
    flat = attr.reshape(-1, C)
    shift = frags.pix_batch * V if attr.dim() == 3 and B > 1 else None
    b = frags.pix_bary.to(attr.dtype)
    out = None
    for i in range(3):
        vid = f[:, i].index_select(0, frags.pix_face)
        rows = flat.index_select(0, vid if shift is None else vid + shift)
        w = b[:, i].contiguous()[:, None]
        out = rows * w if out is None else out.addcmul_(rows, w)
    return out


def interpolate(attr: torch.Tensor, frags: Fragments, faces: torch.Tensor, check: bool = True,
                out: torch.Tensor | None = None) -> torch.Tensor:
    """Interpolate vertex attributes with the perspective-correct barycentrics of ``frags``.

    Only covered pixels are computed (gathered per face, written into a zero image).

    Args:
        attr: (V, C) attributes shared by the batch, or (B, V, C).
        frags: :class:`Fragments` from :func:`relightnet.raster.rasterize`.
        faces: (F, 3) the faces that were rasterized.
        check: validate shapes.
        out: optional contiguous (B, H, W, C) tensor to write into (reused between frames it
            saves allocating, and page-faulting, a large image each frame).

    Returns:
        (B, H, W, C) interpolated attributes, 0 on background; differentiable w.r.t. ``attr``.

    Example:
        A per-vertex attribute at every covered pixel, here each vertex's x in clip space:

        >>> import torch
        >>> from relightnet.raster import interpolate, rasterize
        >>> verts = torch.tensor([[[-1.0, -1.0, 0.0, 1.0], [1.0, -1.0, 0.0, 1.0],
        ...                        [1.0, 1.0, 0.0, 1.0], [-1.0, 1.0, 0.0, 1.0]]])
        >>> faces = torch.tensor([[0, 1, 2], [0, 2, 3]])
        >>> frags = rasterize(verts, faces, (2, 4))
        >>> x = interpolate(verts[0, :, :1], frags, faces)
        >>> x.shape
        torch.Size([1, 2, 4, 1])
        >>> [round(v, 2) for v in x[0, 0, :, 0].tolist()]  # pixel centres at x = -0.75, -0.25, 0.25, 0.75
        [-0.75, -0.25, 0.25, 0.75]
    """
    vals = interpolate_pixels(attr, frags, faces, check=check)
    B, H, W = frags.shape
    C = vals.shape[1]
    if out is None:
        out = torch.zeros(B * H * W, C, dtype=vals.dtype, device=vals.device)
    else:
        check_shape(out, [B, H, W, C], name="out")
        if not out.is_contiguous() or out.dtype != vals.dtype:
            raise InputError(f"out: expected a contiguous {vals.dtype} tensor")
        out = out.view(B * H * W, C).zero_()
    return out.index_copy_(0, frags.pix, vals).view(B, H, W, C)


class Interpolate(nn.Module):
    """Module form of :func:`interpolate` holding the faces as a buffer."""

    def __init__(self, faces: torch.Tensor) -> None:
        super().__init__()
        self.register_buffer("faces", faces.long(), persistent=False)

    def forward(self, attr: torch.Tensor, frags: Fragments) -> torch.Tensor:
        return interpolate(attr, frags, self.faces)


def to_channels_first(x: torch.Tensor) -> torch.Tensor:
    """Rasterizer layout → CNN layout: (B, H, W, C) → (B, C, H, W), or (H, W, C) → (C, H, W).

    Returns a view (no copy; the memory stays channels-last, which convolutions accept).

    Example:
        >>> import torch
        >>> from relightnet.raster import to_channels_first
        >>> to_channels_first(torch.zeros(2, 32, 24, 9)).shape
        torch.Size([2, 9, 32, 24])
    """
    if x.dim() == 4:
        return x.permute(0, 3, 1, 2)
    if x.dim() == 3:
        return x.permute(2, 0, 1)
    raise ShapeError(f"x: expected (B, H, W, C) or (H, W, C), got {tuple(x.shape)}")


def to_channels_last(x: torch.Tensor) -> torch.Tensor:
    """CNN layout → rasterizer layout: (B, C, H, W) → (B, H, W, C), or (C, H, W) → (H, W, C).

    Returns a view (no copy).

    Example:
        >>> import torch
        >>> from relightnet.raster import to_channels_last
        >>> to_channels_last(torch.zeros(3, 32, 24)).shape
        torch.Size([32, 24, 3])
    """
    if x.dim() == 4:
        return x.permute(0, 2, 3, 1)
    if x.dim() == 3:
        return x.permute(1, 2, 0)
    raise ShapeError(f"x: expected (B, C, H, W) or (C, H, W), got {tuple(x.shape)}")
