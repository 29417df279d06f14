"""A video's person masks kept small: each frame's box around the person, bit-packed and deflated.

A fit keeps one mask per frame until its window is fitted. As float32 at the frame's size that is
4 bytes a pixel (50 MB a frame at 12.5 MP), so a long video took gigabytes. :class:`PackedMasks`
keeps only the rows and columns that hold mask pixels, one bit a pixel, deflated: a person's
mask costs about as much as its outline (tens of KB at 12.5 MP), and :meth:`PackedMasks.unpack`
gives the masks back bit for bit, so the fit sees exactly what it saw before.
"""

from __future__ import annotations

import zlib

import numpy as np
import torch

from ..checks import ShapeError

__all__ = ["PackedMasks"]

#: zlib level: 1 packs a person's box (mostly long runs) within a few % of level 9, several times faster.
_LEVEL = 1


def _pack(mask: np.ndarray) -> tuple[int, int, int, int, bytes] | None:
    rows, cols = np.flatnonzero(mask.any(1)), np.flatnonzero(mask.any(0))
    if len(rows) == 0:
        return None
    y0, y1, x0, x1 = int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1
    return y0, y1, x0, x1, zlib.compress(np.packbits(mask[y0:y1, x0:x1]).tobytes(), _LEVEL)


class PackedMasks:
    """T binary (H, W) masks, each stored as the box around its pixels, one bit a pixel, deflated.

    Args:
        size: (H, W) of every mask.

    Append (H, W) masks (bool, or values in {0, 1}: above 0.5 is the person) with :meth:`append`
    or make one from (T, H, W) with :meth:`from_masks`; ``len()`` is T, ``packed[a:b]`` the frames
    [a, b) (sharing the stored bytes), :meth:`unpack` the (T, H, W) bool masks.
    """

    def __init__(self, size: tuple[int, int]) -> None:
        self.size = (int(size[0]), int(size[1]))
        self._items: list[tuple[int, int, int, int, bytes] | None] = []

    @classmethod
    def from_masks(cls, masks) -> PackedMasks:
        """Pack (T, H, W) masks (a tensor or an array; above 0.5 is the person)."""
        if masks.ndim != 3:
            raise ShapeError(f"masks: expected (T, H, W), got shape {tuple(masks.shape)}")
        out = cls(tuple(masks.shape[1:]))
        for m in masks:
            out.append(m)
        return out

    def append(self, mask) -> None:
        """Add one (H, W) mask (a tensor or an array; above 0.5 is the person)."""
        if tuple(mask.shape) != self.size:
            raise ShapeError(f"mask: expected shape {self.size}, got {tuple(mask.shape)}")
        m = mask.detach().cpu().numpy() if isinstance(mask, torch.Tensor) else np.asarray(mask)
        self._items.append(_pack(m if m.dtype == np.bool_ else m > 0.5))

    def append_empty(self) -> None:
        """Add a mask without person pixels (a frame where nobody was found)."""
        self._items.append(None)

    def __len__(self) -> int:
        return len(self._items)

    def __getitem__(self, index: slice) -> PackedMasks:
        if not isinstance(index, slice):
            raise TypeError(f"PackedMasks: index with a slice of frames, got {type(index).__name__}")
        out = PackedMasks(self.size)
        out._items = self._items[index]
        return out

    @property
    def nbytes(self) -> int:
        """Bytes of the packed masks (the deflated bits; the boxes' few integers not counted)."""
        return sum(len(it[4]) for it in self._items if it is not None)

    def unpack(self) -> torch.Tensor:
        """(T, H, W) bool: the masks as they were appended."""
        out = np.zeros((len(self), *self.size), np.bool_)
        for t, it in enumerate(self._items):
            if it is None:
                continue
            y0, y1, x0, x1, data = it
            bits = np.unpackbits(np.frombuffer(zlib.decompress(data), np.uint8), count=(y1 - y0) * (x1 - x0))
            out[t, y0:y1, x0:x1] = bits.reshape(y1 - y0, x1 - x0).view(np.bool_)
        return torch.from_numpy(out)
