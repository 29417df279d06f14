"""``Fragments``: what the rasterizer hands to interpolation and shading."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import torch

from ..checks import ShapeError, check_shape
from .window import Window

__all__ = ["Fragments"]


@dataclass(frozen=True, eq=False)
class Fragments:
    """Per-pixel result of :func:`relightnet.raster.rasterize` (channels-last, B×H×W).

    Stored compactly, for the N covered pixels only (consumers such as
    :func:`relightnet.raster.interpolate` touch nothing else):

    Attributes:
        pix: (N,) int64 flat indices of covered pixels into the B·H·W pixels (each once,
            in no particular order).
        pix_face: (N,) int64 index into ``faces`` of the nearest triangle at each.
        pix_bary: (N, 3) perspective-correct barycentric weights of that triangle's three
            vertices (in the order of ``faces[face]``), summing to 1.
        pix_depth: (N,) NDC depth ``z_clip / w_clip`` in [−1, 1] (−1 on the near plane;
            :meth:`relightnet.raster.Camera.depth_to_view` converts to a distance).
        shape: (B, H, W) the pixel grid: the frame's, or the window's when ``window`` is set.
        window: the :class:`~relightnet.raster.Window` of the frame that was rasterized
            (``rasterize(..., window=)``; flat indices into its B·H·W pixels map to the frame's with
            ``window.to_frame``), or None for the whole frame.

    Dense views, built on first access and cached:

    - ``face_id`` (B, H, W) int64, −1 on background;
    - ``bary`` (B, H, W, 3), 0 on background;
    - ``depth`` (B, H, W), +inf on background;
    - ``mask`` (B, H, W) bool.
    """

    pix: torch.Tensor
    pix_face: torch.Tensor
    pix_bary: torch.Tensor
    pix_depth: torch.Tensor
    shape: tuple[int, int, int]
    window: Window | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "shape", tuple(int(s) for s in self.shape))
        if len(self.shape) != 3:
            raise ShapeError(f"shape: expected (B, H, W), got {self.shape}")
        if self.window is not None and self.window.size != self.shape[1:]:
            raise ShapeError(f"shape: expected (B, {self.window.height}, {self.window.width}) for its window, "
                             f"got {self.shape}")
        dims = check_shape(self.pix, ["N"], name="pix")
        check_shape(self.pix_face, ["N"], name="pix_face", dims=dims)
        check_shape(self.pix_bary, ["N", 3], name="pix_bary", dims=dims)
        check_shape(self.pix_depth, ["N"], name="pix_depth", dims=dims)

    @classmethod
    def from_dense(cls, face_id: torch.Tensor, bary: torch.Tensor, depth: torch.Tensor) -> Fragments:
        """Build Fragments from dense fields (−1 in ``face_id`` marks background).

        Args:
            face_id: (B, H, W) int64.
            bary: (B, H, W, 3).
            depth: (B, H, W).
        """
        dims = check_shape(face_id, ["B", "H", "W"], name="face_id")
        check_shape(bary, ["B", "H", "W", 3], name="bary", dims=dims)
        check_shape(depth, ["B", "H", "W"], name="depth", dims=dims)
        pix = torch.nonzero(face_id.reshape(-1) >= 0).squeeze(1)
        return cls(pix, face_id.reshape(-1).index_select(0, pix), bary.reshape(-1, 3).index_select(0, pix),
                   depth.reshape(-1).index_select(0, pix), tuple(face_id.shape))

    @property
    def size(self) -> tuple[int, int]:
        """(H, W)."""
        return self.shape[1], self.shape[2]

    @property
    def batch_size(self) -> int:
        return self.shape[0]

    @property
    def region(self) -> Window:
        """The part of the frame these fragments cover: their ``window``, or the whole frame."""
        return Window.full(self.size) if self.window is None else self.window

    def frame_pixels(self, pix: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Flat indices into the B·H·W pixels → (batch, row, column) of the frame, each (N,) int64."""
        B, h, w = self.shape
        b = torch.div(pix, h * w, rounding_mode="floor")
        r = pix - b * (h * w)
        row = torch.div(r, w, rounding_mode="floor")
        win = self.region
        return b, row + win.top, r - row * w + win.left

    @property
    def pix_batch(self) -> torch.Tensor:
        """(N,) int64 batch index of every covered pixel."""
        return torch.div(self.pix, self.shape[1] * self.shape[2], rounding_mode="floor")

    def _dense(self, values: torch.Tensor, fill) -> torch.Tensor:
        n = self.shape[0] * self.shape[1] * self.shape[2]
        out = torch.full((n, *values.shape[1:]), fill, dtype=values.dtype, device=values.device)
        return out.index_copy_(0, self.pix, values).view(*self.shape, *values.shape[1:])

    def seen_vertices(self, faces: torch.Tensor, n_verts: int) -> torch.Tensor:
        """Vertices of the faces that are nearest at some covered pixel (what the camera sees).

        Args:
            faces: (F, 3) int64 the faces that were rasterized.
            n_verts: V, the number of vertices.

        Returns:
            (M,) int64 sorted vertex indices, each once (a boolean scatter: no sort of the N pixels).
        """
        check_shape(faces, ["F", 3], name="faces")
        dev = self.pix.device
        hit = torch.zeros(faces.shape[0], dtype=torch.bool, device=dev).index_fill_(0, self.pix_face, True)
        used = faces.to(device=dev, dtype=torch.long)[hit].reshape(-1)
        seen = torch.zeros(int(n_verts), dtype=torch.bool, device=dev).index_fill_(0, used, True)
        return torch.nonzero(seen).squeeze(1)

    @cached_property
    def _order(self) -> tuple[torch.Tensor, torch.Tensor]:
        return torch.sort(self.pix)

    def locate(self, pix: torch.Tensor) -> torch.Tensor:
        """Where pixels are in the compact fields: ``pix_*[locate(p)]`` are pixel p's values.

        A binary search in the sorted covered pixels (sorted once, on first use), no image-sized
        index.

        Args:
            pix: (M,) int64 flat indices into the B·H·W pixels.

        Returns:
            (M,) int64 positions into ``pix``, ``pix_face``, ... ; −1 where a pixel is not covered.
        """
        srt, order = self._order
        if srt.numel() == 0:
            return torch.full_like(pix, -1)
        at = torch.searchsorted(srt, pix).clamp_(max=srt.numel() - 1)
        return torch.where(srt[at] == pix, order[at], torch.full_like(at, -1))

    @cached_property
    def face_id(self) -> torch.Tensor:
        """(B, H, W) int64 nearest triangle per pixel, −1 on background."""
        return self._dense(self.pix_face, -1)

    @cached_property
    def bary(self) -> torch.Tensor:
        """(B, H, W, 3) perspective-correct barycentrics, 0 on background."""
        return self._dense(self.pix_bary, 0)

    @cached_property
    def depth(self) -> torch.Tensor:
        """(B, H, W) NDC depth, +inf on background."""
        return self._dense(self.pix_depth, float("inf"))

    @cached_property
    def mask(self) -> torch.Tensor:
        """(B, H, W) bool: pixels covered by a triangle."""
        n = self.shape[0] * self.shape[1] * self.shape[2]
        out = torch.zeros(n, dtype=torch.bool, device=self.pix.device)
        return out.index_fill_(0, self.pix, True).view(self.shape)
