"""A video's person masks kept small: at the fit's working resolution, the person's box, bit-packed and deflated.

A fit keeps one mask per frame until its window is fitted. As float32 at the frame's size that is
4 bytes a pixel (50 MB a frame at 12.5 MP), so a long video took gigabytes. :class:`PackedMasks`
keeps only the rows and columns that hold mask pixels, one bit a pixel, deflated; given the fit's
``window``, it also resamples each complete window of frames to the working resolution the fit's
silhouette term uses for that window (:func:`relightnet.fit.terms.working_size`: the person about
:data:`~relightnet.fit.masks.SILHOUETTE_HEIGHT` pixels tall) as soon as the window is complete, with the
same resampling the fit did later before. A frame then costs at most :data:`MAX_FRAME_BYTES` (the
incompressible bits of the largest working box, ~28 KiB), whatever the frame's size; a person's
mask about its outline at 240 px (~1 KB). :meth:`PackedMasks.working` gives a window's masks at its
working resolution: bit for bit what the fit resampled from the full-size masks before.
"""

from __future__ import annotations

import zlib

import numpy as np
import torch
import torch.nn.functional as F

from ..checks import InputError, ShapeError
from .terms import SILHOUETTE_HEIGHT, WORK_ASPECT, working_size

__all__ = ["PackedMasks", "MAX_FRAME_BYTES"]

#: zlib level: 1 packs a person's box (mostly long runs) within a few % of level 9, several times faster.
_LEVEL = 1

#: Most bytes one frame's mask holds once resampled to the working resolution: the largest working box,
#: (H + 2) × (4 H + 2) bits at H = :data:`SILHOUETTE_HEIGHT` (area resampling can touch one more row or
#: column at each side), deflate's few bytes for incompressible data added: 29,165 bytes (~28.5 KiB).
MAX_FRAME_BYTES = (SILHOUETTE_HEIGHT + 2) * (WORK_ASPECT * SILHOUETTE_HEIGHT + 2) // 8 + 64


def _pack(mask: np.ndarray, grid: tuple[int, int], extent=None) -> tuple | None:
    """(box, data, grid, extent): the box (y0, y1, x0, x1) in ``grid``, its deflated bits, and the box
    at the frames' full size (``extent``; the box itself for a mask at full size)."""
    rows, cols = np.flatnonzero(mask.any(1)), np.flatnonzero(mask.any(0))
    if len(rows) == 0:
        return None if extent is None else ((0, 0, 0, 0), b"", grid, extent)
    box = (int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1)
    data = zlib.compress(np.packbits(mask[box[0]:box[1], box[2]:box[3]]).tobytes(), _LEVEL)
    return box, data, grid, box if extent is None else extent


def _bits(item, grid: tuple[int, int]) -> np.ndarray:
    """(h, w) bool: one stored mask on ``grid`` (its own bits there, else area-resampled, then > 0.5)."""
    (y0, y1, x0, x1), data, own, _ = item
    out = np.zeros(own, np.bool_)
    if y1 > y0:
        bits = np.unpackbits(np.frombuffer(zlib.decompress(data), np.uint8), count=(y1 - y0) * (x1 - x0))
        out[y0:y1, x0:x1] = bits.reshape(y1 - y0, x1 - x0).view(np.bool_)
    if tuple(own) == tuple(grid):
        return out
    return (F.interpolate(torch.from_numpy(out).float()[None, None], size=grid, mode="area")[0, 0] > 0.5).numpy()


class PackedMasks:
    """T binary (H, W) masks, each stored as the box around its pixels, one bit a pixel, deflated.

    Args:
        size: (H, W) of the frames.
        window: the fit's window (frames fitted together, counted from the first): each complete
            window of appended masks is resampled to its working resolution
            (:func:`relightnet.fit.terms.working_size`), at most :data:`MAX_FRAME_BYTES` a frame; the frames of
            the window being appended (the video's last window, short) stay at (H, W) until it is complete
            (at most ``window`` − 1 frames: ≤ 12.5 MB within :data:`~relightnet.fit.solve.MAX_WINDOW_PIXELS`).
            None: masks are kept at (H, W).
        height: the working height of the person (:data:`~relightnet.fit.masks.SILHOUETTE_HEIGHT`).

    Append (H, W) masks (bool, or values in {0, 1}: above 0.5 is the person) with :meth:`append`
    or make one from (T, H, W) with :meth:`from_masks`; ``len()`` is T, ``packed[a:b]`` the frames
    [a, b) (sharing the stored bytes), :meth:`working` a window's (T, h, w) masks at its working
    resolution, :meth:`unpack` the (T, H, W) bool masks.
    """

    def __init__(self, size: tuple[int, int], window: int | None = None, height: int = SILHOUETTE_HEIGHT) -> None:
        if window is not None and int(window) < 1:
            raise InputError(f"window: expected >= 1 frames, got {window}")
        self.size = (int(size[0]), int(size[1]))
        self.window, self.height = (None if window is None else int(window)), int(height)
        self._items: list[tuple | None] = []
        self._start = 0  # the first frame of the window being appended

    @classmethod
    def from_masks(cls, masks) -> PackedMasks:
        """Pack (T, H, W) masks (a tensor or an array; above 0.5 is the person), kept at (H, W)."""
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
        self._items.append(_pack(m if m.dtype == np.bool_ else m > 0.5, self.size))
        self._window_done()

    def append_empty(self) -> None:
        """Add a mask without person pixels (a frame where nobody was found)."""
        self._items.append(None)
        self._window_done()

    def _window_done(self) -> None:
        """Resample the window just completed to its working resolution (one frame at a time)."""
        if self.window is None or len(self._items) - self._start < self.window:
            return
        part = self._items[self._start:]
        grid = self.grid(part)
        if grid != self.size:
            self._items[self._start:] = [None if it is None else _pack(_bits(it, grid), grid, it[3]) for it in part]
        self._start = len(self._items)

    def grid(self, items=None) -> tuple[int, int]:
        """(h, w): the working resolution of these frames fitted together (:func:`relightnet.fit.terms.working_size`
        of the box around all their full-size boxes)."""
        ext = [it[3] for it in (self._items if items is None else items) if it is not None]
        rows = max(e[1] for e in ext) - min(e[0] for e in ext) if ext else 0
        cols = max(e[3] for e in ext) - min(e[2] for e in ext) if ext else 0
        return working_size(self.size, rows, cols, self.height)

    def __len__(self) -> int:
        return len(self._items)

    def __getitem__(self, index: slice) -> PackedMasks:
        if not isinstance(index, slice):
            raise TypeError(f"PackedMasks: index with a slice of frames, got {type(index).__name__}")
        out = PackedMasks(self.size, None, self.height)
        out._items = self._items[index]
        return out

    @property
    def nbytes(self) -> int:
        """Bytes of the packed masks (the deflated bits; the boxes' few integers not counted)."""
        return sum(len(it[1]) for it in self._items if it is not None)

    def working(self) -> tuple[torch.Tensor, tuple[float, float]]:
        """(T, h, w) bool masks at these frames' working resolution (:meth:`grid`) and the factors (x, y)
        image pixels → working pixels. Frames stored at that resolution are given bit for bit; others
        are resampled (area average, then > 0.5), as :func:`relightnet.fit.terms.silhouette_targets` does."""
        grid = self.grid()
        out = np.zeros((len(self), *grid), np.bool_)
        for t, it in enumerate(self._items):
            if it is not None:
                out[t] = _bits(it, grid)
        return torch.from_numpy(out), (grid[1] / self.size[1], grid[0] / self.size[0])

    def unpack(self) -> torch.Tensor:
        """(T, H, W) bool: the masks at the frames' size (those stored at a working resolution enlarged)."""
        out = np.zeros((len(self), *self.size), np.bool_)
        for t, it in enumerate(self._items):
            if it is not None:
                out[t] = _bits(it, self.size)
        return torch.from_numpy(out)
