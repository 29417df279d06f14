"""Person masks for a video: the crop follows the previous frame's mask.

Finding the person anew in every frame (the selfie model's loose box) moves the pose model's
crop from frame to frame, and the mask's outline flickers with it. :class:`PersonTracker`
finds the person once, then takes each frame's crop from the mask of the frame before
(as a hand-made mask follows the person), smoothed a little over time; it searches the
whole frame again only when the person is lost.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import torch

from ..checks import InputError
from .models import PersonModels
from .person import PersonMask, crop_around, find_person, mask_box, refine_person, segment_crop

__all__ = ["PersonTracker", "track_person"]


class PersonTracker:
    """Segment one person frame after frame (call it on each frame in order).

    Args:
        models: loaded :class:`PersonModels` (made here when None).
        smoothing: weight of the new crop in the running crop (1: the previous mask's crop as is).
        refine: reads around its own mask when the person is (re)found (as :func:`segment_person`).

    Calling it on a (3, H, W) sRGB frame in [0, 1] returns a :class:`PersonMask`, or None when
    no person is in the frame.
    """

    def __init__(self, models: PersonModels | None = None, smoothing: float = 0.5, refine: int = 2) -> None:
        if not 0 < smoothing <= 1:
            raise InputError(f"smoothing: expected a weight in (0, 1], got {smoothing}")
        self.models = models if models is not None else PersonModels()
        self.smoothing, self.refine = smoothing, refine
        self._crop: tuple[float, float, float] | None = None

    def reset(self) -> None:
        """Forget the person (the next frame is searched whole)."""
        self._crop = None

    def _blend(self, crop: tuple[float, float, float]) -> tuple[float, float, float]:
        if self._crop is None:
            return crop
        a = self.smoothing
        return tuple(a * n + (1 - a) * o for n, o in zip(crop, self._crop, strict=True))

    def __call__(self, frame: torch.Tensor) -> PersonMask | None:
        res = None
        if self._crop is not None:
            res = segment_crop(frame, self._crop, self.models)
        if res is None:  # first frame, or the person was lost: search the whole frame, as in a photo
            self._crop = None
            res = find_person(frame, self.models)
            if res is not None:
                res = refine_person(frame, res, self.models, self.refine)
        self._crop = None if res is None else self._blend(crop_around(mask_box(res.mask)))
        return res


def track_person(frames: Iterable[torch.Tensor], models: PersonModels | None = None, smoothing: float = 0.5,
                 allow_empty: bool = True, name: str = "video",
                 ) -> Iterator[tuple[torch.Tensor, PersonMask | None]]:
    """:class:`PersonTracker` over (3, H, W) frames in order: yields (frame, result or None).

    Raises:
        InputError: ``"{name}: frame t (counting from 0): no person found"`` unless ``allow_empty``.
    """
    tracker = PersonTracker(models, smoothing)
    for t, frame in enumerate(frames):
        res = tracker(frame)
        if res is None and not allow_empty:
            raise InputError(f"{name}: frame {t} (counting from 0): no person found")
        yield frame, res
