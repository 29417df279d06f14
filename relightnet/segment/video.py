"""Person masks for a video: the crop follows the previous frame's mask, and the mask is held steady.

Finding the person anew in every frame (the selfie model's loose box) moves the pose model's
crop from frame to frame, and the mask's outline flickers with it. :class:`PersonTracker`
finds the person once, then takes each frame's crop from the mask of the frame before
(as a hand-made mask follows the person), smoothed a little over time; it searches the
whole frame again only when the person is lost. Each mask after the first is then filtered
over time (:mod:`.steady`): the previous mask, carried along the motion of the landmarks,
keeps the pixels whose probability is within ``steady`` of one half as they were, so the
outline stops shimmering without lagging a moving arm.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import replace

import numpy as np
import torch

from ..checks import InputError
from .flow import gray_u8
from .models import PersonModels
from .person import (
    PersonMask,
    _largest_region,
    crop_around,
    crop_pixels,
    find_person,
    mask_box,
    refine_person,
    segment_crop,
)
from .steady import MASK_CARRY, STEADY_MARGIN, carry_mask, flow_carry, hysteresis, landmark_motion

__all__ = ["PersonTracker", "track_person"]


def _crop_motion(prev: tuple[float, float, float], cur: tuple[float, float, float],
                 ) -> tuple[float, float, float, float]:
    """(sx, sy, tx, ty) taking one square crop (cx, cy, side) onto another."""
    s = cur[2] / prev[2]
    return s, s, cur[0] - s * prev[0], cur[1] - s * prev[1]


def _window(crop: tuple[float, float, float], h: int, w: int) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1) of a square crop clipped to the frame (where its probability can be non-zero)."""
    x0, y0, s = crop_pixels(crop)
    return max(x0, 0), max(y0, 0), min(x0 + s, w), min(y0 + s, h)


def steady_person(res: PersonMask, prev: PersonMask | None, margin: float, frames=None) -> PersonMask:
    """``res`` with its mask held by the previous frame's (:mod:`.steady`): ``prev``'s mask carried
    along the landmarks' motion (the crops' when fewer than 3 landmarks are seen in both) — with
    ``frames``, along the optical flow where it is reliable and blended into the probability there
    (:func:`~relightnet.segment.steady.flow_carry`) — then the hysteresis of ``margin`` and the largest
    region. ``prev`` None or ``margin`` 0: ``res`` as is.

    Args:
        res, prev: this frame's and the previous frame's results ((H, W) masks, (33, 5) landmarks).
        margin: the hysteresis margin on the probability, in [0, 0.5).
        frames: ``(previous, current)`` (H, W) uint8 gray frames, or None (the landmarks only).

    Returns:
        ``res`` with the steady (H, W) mask; ``probability`` is left as the model gave it.
    """
    if prev is None or margin <= 0:
        return res
    motion = landmark_motion(prev.landmarks, res.landmarks) or _crop_motion(prev.crop, res.crop)
    h, w = res.mask.shape
    x0, y0, x1, y1 = win = _window(res.crop, h, w)  # the probability is 0 outside: work inside only
    carried = carry_mask(prev.mask, motion, win)[y0:y1, x0:x1]
    prob = res.probability[y0:y1, x0:x1]
    if frames is not None and x1 - x0 >= 8 and y1 - y0 >= 8:
        soft, rel = flow_carry(frames[0], frames[1], prev.mask, win)
        p = prob.numpy()
        prob = torch.from_numpy((p + MASK_CARRY * rel * (soft - p)).astype(np.float32))
        carried = torch.from_numpy(np.where(rel > 0.5, soft > 0.5, carried.numpy()))
    region = _largest_region(hysteresis(prob, carried, margin).numpy())
    if region is None:
        return res
    mask = np.zeros((h, w), np.float32)  # numpy: no torch thread pool for a copy (a busy machine)
    mask[y0:y1, x0:x1] = region
    return replace(res, mask=torch.from_numpy(mask))


class PersonTracker:
    """Segment one person frame after frame (call it on each frame in order).

    Args:
        models: loaded :class:`PersonModels` (made here when None).
        smoothing: weight of the new crop in the running crop (1: the previous mask's crop as is).
        refine: reads around its own mask when the person is (re)found (as :func:`segment_person`).
        steady: hysteresis margin of the temporal mask filter (:func:`steady_person`; 0: off;
            default :data:`~relightnet.segment.steady.STEADY_MARGIN`, 0.15).
        flow: carry the previous mask along the optical flow between the frames (False: along the
            landmarks' motion only).

    Calling it on a (3, H, W) sRGB frame in [0, 1] returns a :class:`PersonMask`, or None when
    no person is in the frame.
    """

    def __init__(self, models: PersonModels | None = None, smoothing: float = 0.5, refine: int = 2,
                 steady: float = STEADY_MARGIN, flow: bool = True) -> None:
        if not 0 < smoothing <= 1:
            raise InputError(f"smoothing: expected a weight in (0, 1], got {smoothing}")
        if not 0 <= steady < 0.5:
            raise InputError(f"steady: expected a probability margin in [0, 0.5), got {steady}")
        self.models = models if models is not None else PersonModels()
        self.smoothing, self.refine, self.steady, self.flow = smoothing, refine, steady, bool(flow)
        self._crop: tuple[float, float, float] | None = None
        self._prev: PersonMask | None = None
        self._gray: np.ndarray | None = None  # the previous frame's gray levels (with ``flow``)

    def reset(self) -> None:
        """Forget the person (the next frame is searched whole, without history)."""
        self._crop = None
        self._prev = None

    def _blend(self, crop: tuple[float, float, float]) -> tuple[float, float, float]:
        if self._crop is None:
            return crop
        a = self.smoothing
        return tuple(a * n + (1 - a) * o for n, o in zip(crop, self._crop, strict=True))

    def __call__(self, frame: torch.Tensor) -> PersonMask | None:
        res = None
        gray = gray_u8(frame) if self.flow else None
        if self._crop is not None:
            res = segment_crop(frame, self._crop, self.models)
            if res is not None:
                pair = (self._gray, gray) if gray is not None and self._gray is not None \
                    and self._gray.shape == gray.shape else None
                res = steady_person(res, self._prev, self.steady, pair)
        self._gray = gray
        if res is None:  # first frame, or the person was lost: search the whole frame, as in a photo
            self.reset()
            res = find_person(frame, self.models)
            if res is not None:
                res = refine_person(frame, res, self.models, self.refine)
        self._prev = res
        self._crop = None if res is None else self._blend(crop_around(mask_box(res.mask)))
        return res


def track_person(frames: Iterable[torch.Tensor], models: PersonModels | None = None, smoothing: float = 0.5,
                 allow_empty: bool = True, name: str = "video", steady: float = STEADY_MARGIN,
                 ) -> Iterator[tuple[torch.Tensor, PersonMask | None]]:
    """:class:`PersonTracker` over (3, H, W) frames in order: yields (frame, result or None).

    Raises:
        InputError: ``"{name}: frame t (counting from 0): no person found"`` unless ``allow_empty``.
    """
    tracker = PersonTracker(models, smoothing, steady=steady)
    for t, frame in enumerate(frames):
        res = tracker(frame)
        if res is None and not allow_empty:
            raise InputError(f"{name}: frame {t} (counting from 0): no person found")
        yield frame, res
