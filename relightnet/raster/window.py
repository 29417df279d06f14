"""``Window``: a rectangle of whole pixels of a frame, rasterized on its own.

``rasterize(..., window=w)`` computes the fragments of the frame's pixels inside ``w`` only, bit for
bit what rasterizing the whole frame gives there (:func:`relightnet.raster.rasterize`); every buffer
of the render is then the window's size. :func:`relightnet.raster.screen_box` finds the window that
holds everything a mesh can cover.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from ..checks import InputError

__all__ = ["Window"]


@dataclass(frozen=True)
class Window:
    """Rows ``top .. top + height − 1`` and columns ``left .. left + width − 1`` of an (H, W) frame.

    Pixel (i, j) of the window is pixel (top + i, left + j) of the frame (pixel convention of
    :mod:`relightnet.raster.camera`); a window's flat pixel indices run over B·height·width.

    Attributes:
        top, left: the frame's row and column of the window's pixel (0, 0).
        height, width: the window's size, at least 1 each.
        frame: (H, W) the frame's size.
    """

    top: int
    left: int
    height: int
    width: int
    frame: tuple[int, int]

    def __post_init__(self) -> None:
        for name in ("top", "left", "height", "width"):
            object.__setattr__(self, name, int(getattr(self, name)))
        object.__setattr__(self, "frame", (int(self.frame[0]), int(self.frame[1])))
        H, W = self.frame
        if not (0 <= self.top and 1 <= self.height and self.top + self.height <= H
                and 0 <= self.left and 1 <= self.width and self.left + self.width <= W):
            raise InputError(f"window: rows {self.top}+{self.height}, columns {self.left}+{self.width} "
                             f"do not lie in a ({H}, {W}) frame")

    @classmethod
    def full(cls, size) -> Window:
        """The whole (H, W) frame."""
        return cls(0, 0, int(size[0]), int(size[1]), (int(size[0]), int(size[1])))

    @property
    def size(self) -> tuple[int, int]:
        """(height, width)."""
        return self.height, self.width

    @property
    def is_full(self) -> bool:
        """Whether the window is the whole frame."""
        return self.size == self.frame

    def slices(self) -> tuple[slice, slice]:
        """(rows, columns) that cut the window out of a (..., H, W[, C]) frame array: ``frame[..., r, c]``
        for channels-first, ``frame[r, c]`` for an (H, W, C) image."""
        return slice(self.top, self.top + self.height), slice(self.left, self.left + self.width)

    def to_frame(self, pix: torch.Tensor) -> torch.Tensor:
        """Flat indices into the window's B·height·width pixels → the same pixels' flat indices into B·H·W.

        Args:
            pix: (N,) int64.

        Returns:
            (N,) int64.
        """
        if self.is_full:
            return pix
        H, W = self.frame
        per = self.height * self.width
        b = torch.div(pix, per, rounding_mode="floor")
        r = pix - b * per
        row = torch.div(r, self.width, rounding_mode="floor")
        col = r - row * self.width
        return (b * H + row + self.top) * W + col + self.left
