"""The CNN's maps carried along the optical flow from frame to frame: relit video without added flicker.

Each frame of ``relight-video`` is relit by the ratio of its shading under the new light to its
shading under the source light, both from the CNN's per-pixel transport. The CNN sees every
frame afresh, so where the person barely moves its transport still changes a little from frame to
frame, and the relit person flickers more than the footage does. :class:`MapCarry` carries the
previous frame's transport (and albedo, which the photo albedo falls back on in the dark) along
the optical flow (:func:`relightnet.segment.flow.backward_flow`, computed at the CNN's working
size inside the current frame's crop) and blends them into the new prediction where the flow is
reliable and both frames show the person there (the same for the albedo):

    T̃_t = T_t + c · w · (warp(T̃_{t−1}) − T_t)

with ``c`` = :data:`CARRY` and ``w`` the flow's reliability times both masks. Where the person
moves, the flow moves the carried maps with them; where the flow fails (an occlusion, a fast
turn, motion blur) the new prediction is kept. The carry is causal (the previous frame only), so
it streams with the video; a reset (a frame without the person) starts afresh.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import torch
import torch.nn.functional as F

from ..checks import InputError
from ..model.inference import CropBox, CropMaps, crop_to_box
from ..segment.flow import backward_flow, gray_u8, sample_along

__all__ = ["CARRY", "MapCarry", "carry_positions"]

#: The weight of the carried transport where the flow is fully reliable: an average along the motion
#: over about 1 / (1 − CARRY) = 10 frames.
CARRY = 0.9


def _crop_at(image: torch.Tensor, box: CropBox, size: int) -> torch.Tensor:
    """(H, W) map (float, or uint8 gray read as /255) → (size, size) float: the box's crop resized
    (antialiased bilinear; only the box is converted to float)."""
    crop = crop_to_box(image[None, None], box).float()
    if image.dtype == torch.uint8:
        crop = crop.div_(255)
    return F.interpolate(crop, size=(size, size), mode="bilinear", align_corners=False, antialias=True)[0, 0]


def carry_positions(flow: np.ndarray, box: CropBox, previous_box: CropBox, size: int,
                    previous_size: int) -> torch.Tensor:
    """Where each pixel of the current crop was in the previous crop's maps.

    Args:
        flow: (s, s, 2) backward flow in pixels of the current crop at its working size ``size``.
        box, previous_box: the crops (of the frames) the current and previous maps were made from.
        previous_size: the working size of the previous maps.

    Returns:
        (s, s, 2) (x, y) pixel positions in the previous maps.
    """
    s = int(size)
    u = torch.arange(s, dtype=torch.float64)
    grid = torch.stack(torch.meshgrid(u, u, indexing="xy"), -1) + torch.from_numpy(flow).double()
    f = box.size / s  # frame pixels per crop pixel
    frame = torch.stack([box.left + (grid[..., 0] + 0.5) * f - 0.5, box.top + (grid[..., 1] + 0.5) * f - 0.5], -1)
    g = previous_size / previous_box.size
    return torch.stack([(frame[..., 0] - previous_box.left + 0.5) * g - 0.5,
                        (frame[..., 1] - previous_box.top + 0.5) * g - 0.5], -1).float()


class MapCarry:
    """Streaming carry of the CNN's transport along the flow (module docstring).

    ``carry(image (3, H, W) float sRGB, maps: CropMaps) -> CropMaps`` (the transport and the albedo
    replaced, the rest as predicted); :meth:`reset` forgets the previous frame.
    """

    def __init__(self, carry: float = CARRY) -> None:
        if isinstance(carry, bool) or not 0 <= float(carry) < 1:
            raise InputError(f"carry: expected a weight in [0, 1), got {carry!r}")
        self.carry = float(carry)
        self._prev = None  # (gray frame (H, W) uint8, box, transport and albedo (1, K + 3, s, s), mask crop)

    def reset(self) -> None:
        self._prev = None

    def __call__(self, image: torch.Tensor, maps: CropMaps) -> CropMaps:
        s = int(maps.transport.shape[-1])
        gray = torch.from_numpy(gray_u8(image))
        mask = _crop_at(maps.mask[0, 0].float(), maps.box, s)[None, None]
        prev, self._prev = self._prev, None
        if self.carry > 0 and prev is not None and prev[0].shape == gray.shape:
            p_gray, p_box, p_maps, p_mask = prev
            cur = _crop_at(gray, maps.box, s)
            seen = _crop_at(p_gray, maps.box, s)  # the previous frame through the current crop
            flow = backward_flow(seen, cur)
            pos = carry_positions(flow.flow, maps.box, p_box, s, int(p_maps.shape[-1]))
            k = maps.transport.shape[1]
            carried = sample_along(torch.cat([p_maps, p_mask], 1).float(), pos)
            w = self.carry * torch.from_numpy(flow.reliability)[None, None] * carried[:, -1:].clamp(0, 1) * mask
            now = torch.cat([maps.transport, maps.albedo], 1)
            now = now + w.to(now.dtype) * (carried[:, :-1].to(now.dtype) - now)
            maps = replace(maps, transport=now[:, :k], albedo=now[:, k:])
        self._prev = (gray, maps.box, torch.cat([maps.transport, maps.albedo], 1), mask)
        return maps
