"""Whether a video's camera moves: the global translation between frames by phase correlation.

``avatar --replace-person`` builds its clean plate as a per-pixel temporal median
(:mod:`.clean_plate`), which holds only when every pixel sees the same point of the scene in every
frame. On handheld or panning footage the median smears the whole background, so the job checks
the camera first (:func:`check_fixed_camera`) and refuses a camera that moves. A pan is not
registered or stitched into a panorama: that is not done.

1. **Thumbnails** (:func:`thumbnail`). A frame becomes grayscale (Rec. 601 luma), averaged over
   square blocks of an integer side so that its longest side is at most :data:`THUMB_SIDE` pixels;
   the person's mask becomes the blocks it touches, grown by one block (the person's outline,
   shadow and motion blur).
2. **Phase correlation** (:func:`phase_shift`). The pixels the person covers in either thumbnail
   get weight 0 (they carry no texture, so the person's own motion does not count), rising
   smoothly to 1 over 8 pixels outside them (a hard edge around the person, at the same place in
   both frames when the camera follows the person, would pull the peak toward zero); each
   thumbnail, less its weighted mean, times the weight, is multiplied by a Hann window; the
   cross-power spectrum is normalised to unit magnitude (phase only) and multiplied by a Gaussian
   of 1 pixel, so that its inverse transform is a sampled Gaussian centred at the shift. The peak
   is refined to sub-pixel by a parabola through the logarithms of the peak and its two neighbours
   along each axis (exact for a Gaussian).
3. **Decision** (:func:`check_fixed_camera`). Each sampled frame is compared with the first; the
   camera moves when the largest shift exceeds :data:`MOTION_SHARE` of the frame's width (1 %:
   19 px at 1920 wide, 2 px at 192). A frame that no longer overlaps the first gives a random peak,
   almost always far from zero: refused as well.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..checks import InputError

__all__ = ["THUMB_SIDE", "MOTION_SHARE", "EARLY_FRAMES", "Thumbnail", "thumbnail", "phase_shift",
           "shifts_to_first", "check_fixed_camera"]

#: The longest side of the thumbnails the shifts are measured on, in pixels (at most).
THUMB_SIDE = 256
#: The camera moves when a sampled frame is shifted against the first by more than this share of the width.
MOTION_SHARE = 0.01
#: Frames at the start of the target that ``--replace-person`` checks before any expensive work.
EARLY_FRAMES = 60
#: Width (standard deviation, thumbnail pixels) of the Gaussian the correlation peak is shaped into.
_SIGMA = 1.0
#: Thumbnail pixels over which the weight rises from 0 (the person) to 1.
_TAPER = 8


@dataclass(frozen=True, eq=False)
class Thumbnail:
    """A frame reduced for phase correlation: ``gray`` (h, w) float32 luma in [0, 255], ``person`` (h, w)
    bool the blocks the person touches (grown by one), ``scale`` frame pixels per thumbnail pixel."""

    gray: np.ndarray
    person: np.ndarray
    scale: int


def _blocks(x: np.ndarray, s: int) -> np.ndarray:
    """(H, W) → (H // s, W // s, s, s): the s × s blocks of an image (the remainder rows and columns dropped)."""
    h, w = x.shape[0] // s, x.shape[1] // s
    return x[:h * s, :w * s].reshape(h, s, w, s).swapaxes(1, 2)


def thumbnail(frame, mask=None, side: int = THUMB_SIDE) -> Thumbnail:
    """The :class:`Thumbnail` of one frame (module docstring, step 1).

    Args:
        frame: (H, W, 3) uint8 (or float in [0, 255]) frame.
        mask: (H, W) person mask (values > 0.5 = person), or None (no person).
        side: the thumbnail's longest side, at most.
    """
    f = np.asarray(frame)
    if f.ndim != 3 or f.shape[2] != 3:
        raise InputError(f"camera motion: expected an (H, W, 3) frame, got {f.shape}")
    s = max(1, math.ceil(max(f.shape[:2]) / side))
    if min(f.shape[:2]) < 8 * s:
        raise InputError(f"camera motion: frame {f.shape[:2]} is too small to measure a shift")
    luma = f[..., 0] * np.float32(0.299) + f[..., 1] * np.float32(0.587) + f[..., 2] * np.float32(0.114)
    gray = _blocks(luma, s).mean(axis=(2, 3), dtype=np.float32)
    if mask is None:
        return Thumbnail(gray, np.zeros(gray.shape, bool), s)
    m = np.asarray(mask)
    if m.shape != f.shape[:2]:
        raise InputError(f"camera motion: mask {m.shape} differs from the frame {f.shape[:2]}")
    person = np.pad(_blocks(m > 0.5, s).any(axis=(2, 3)), 1)
    grown = np.zeros(gray.shape, bool)
    for dy in range(3):
        for dx in range(3):
            grown |= person[dy:dy + gray.shape[0], dx:dx + gray.shape[1]]
    return Thumbnail(gray, grown, s)


def _log_vertex(lo: float, mid: float, hi: float) -> float:
    """The vertex offset (in [-0.5, 0.5]) of the parabola through the logs of three samples around a peak."""
    a, b, c = (math.log(max(v, 1e-12)) for v in (lo, mid, hi))
    den = a - 2 * b + c
    return 0.0 if den >= 0 else float(np.clip(0.5 * (a - c) / den, -0.5, 0.5))


def phase_shift(a: np.ndarray, b: np.ndarray, valid: np.ndarray | None = None) -> tuple[float, float]:
    """The translation (dy, dx) in pixels that takes image ``a`` to ``b`` (``b[y, x] ≈ a[y − dy, x − dx]``)
    by phase correlation (module docstring, step 2); shifts beyond half the size wrap around.

    Args:
        a, b: (H, W) float images of the same size.
        valid: (H, W) bool pixels to correlate (the others get weight 0, tapered: module docstring), or None.
    """
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if a.ndim != 2 or a.shape != b.shape:
        raise InputError(f"phase shift: expected two (H, W) images of one size, got {a.shape} and {b.shape}")
    H, W = a.shape
    if valid is not None and np.shape(valid) != a.shape:
        raise InputError(f"phase shift: valid {np.shape(valid)} differs from the images' {a.shape}")
    if valid is not None and not np.any(valid):
        raise InputError("phase shift: no valid pixel to correlate")
    win = np.outer(np.hanning(H), np.hanning(W))
    A, B = (np.fft.rfft2(_centred(x, valid) * win) for x in (a, b))
    R = B * np.conj(A)
    R /= np.maximum(np.abs(R), 1e-12 * np.abs(R).max() + 1e-300)
    fy, fx = np.fft.fftfreq(H)[:, None], np.fft.rfftfreq(W)[None, :]
    r = np.fft.irfft2(R * np.exp(-2 * math.pi**2 * _SIGMA**2 * (fy**2 + fx**2)), s=(H, W))
    iy, ix = np.unravel_index(int(np.argmax(r)), r.shape)
    dy = iy + _log_vertex(r[iy - 1, ix], r[iy, ix], r[(iy + 1) % H, ix])
    dx = ix + _log_vertex(r[iy, ix - 1], r[iy, ix], r[iy, (ix + 1) % W])
    return (dy - H if dy > H / 2 else dy), (dx - W if dx > W / 2 else dx)


def _box(x: np.ndarray, r: int) -> np.ndarray:
    """The mean of ``x`` over a (2r + 1)² square around each pixel (zero outside), by cumulative sums."""
    k = 2 * r + 1
    for axis in (0, 1):
        c = np.cumsum(np.pad(x, [(r + 1, r) if a == axis else (0, 0) for a in (0, 1)]), axis=axis)
        n = c.shape[axis]
        x = (np.take(c, np.arange(k, n), axis) - np.take(c, np.arange(n - k), axis)) / k
    return x


def _centred(x: np.ndarray, valid: np.ndarray | None) -> np.ndarray:
    """``x`` less its mean, weighted: 0 on the invalid pixels, rising to 1 over :data:`_TAPER` pixels
    outside them (a hard hole's edge, at the same place in both images, would pull the peak toward 0)."""
    if valid is None:
        return x - x.mean()
    w = np.clip(2 * _box(valid.astype(np.float64), _TAPER) - 1, 0, 1) ** 2 * valid
    if not w.any():
        w = valid.astype(np.float64)
    return (x - (x * w).sum() / w.sum()) * w


def shifts_to_first(thumbs: Sequence[Thumbnail]) -> np.ndarray:
    """(N, 2) shifts (dy, dx) in frame pixels of each thumbnail against the first (the first's is 0), the
    person's blocks in either left out (:func:`phase_shift`)."""
    if not thumbs:
        raise InputError("camera motion: no frame to compare")
    ref = thumbs[0]
    out = np.zeros((len(thumbs), 2))
    for i, t in enumerate(thumbs[1:], 1):
        if t.gray.shape != ref.gray.shape:
            raise InputError(f"camera motion: frame sizes differ ({t.gray.shape} and {ref.gray.shape} thumbnails)")
        valid = ~(ref.person | t.person)
        if valid.mean() > 0.05:  # the person fills the frame in both: nothing to compare
            out[i] = np.asarray(phase_shift(ref.gray, t.gray, valid)) * ref.scale
    return out


def check_fixed_camera(name, thumbs: Sequence[Thumbnail], frames: Sequence[int], width: int,
                       share: float = MOTION_SHARE) -> np.ndarray:
    """Refuse a moving camera: raise :class:`~relightnet.checks.InputError` naming ``name`` (the video),
    the largest shift and its frames when a thumbnail is shifted against the first by more than ``share``
    of ``width`` (module docstring, step 3).

    Args:
        name: the video, for the message. thumbs: the frames' :class:`Thumbnail`. frames: their indices in
            the video. width: the frame's width in pixels.

    Returns:
        (N, 2) the shifts (:func:`shifts_to_first`) when the camera is fixed.
    """
    if len(frames) != len(thumbs):
        raise InputError(f"camera motion: {len(thumbs)} thumbnails for {len(frames)} frame indices")
    shifts = shifts_to_first(thumbs)
    size = np.hypot(shifts[:, 0], shifts[:, 1])
    worst = int(np.argmax(size))
    if size[worst] > share * width:
        raise InputError(f"{name}: the camera moves ({size[worst]:.0f} px between frames {frames[0]} and "
                         f"{frames[worst]}): --replace-person needs a fixed camera")
    return shifts
