"""What the fit sees: per-frame landmarks, world landmarks and person masks.

:class:`Observations` holds a photo's or a video's evidence (T = 1 for a photo);
:func:`observe_frames` makes it with the shipped person segmentation (the largest person,
the video tracker of :mod:`relightnet.segment.video`), and :func:`fill_missing` interpolates
the landmarks of frames where no person was found (they are flagged, and their mask is empty).
The masks are kept packed (:class:`~relightnet.fit.masks.PackedMasks`: the person's box, one bit a
pixel, deflated), each window of frames resampled to the fit's working resolution as soon as it is
segmented, so a video's evidence grows by at most :data:`~relightnet.fit.masks.MAX_FRAME_BYTES` a
frame (~1 KB for a person's mask), not by a frame.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

import torch

from ..checks import InputError, ShapeError, check_shape
from ..segment.models import LANDMARK_NAMES
from .masks import PackedMasks

__all__ = ["Observations", "observe_frames", "fill_missing", "world_to_view_axes"]

_N = len(LANDMARK_NAMES)


@dataclass(frozen=True, eq=False)
class Observations:
    """Evidence of T frames of size (H, W).

    Attributes:
        landmarks: (T, 33, 5) x, y pixels, z, visibility, presence (:class:`relightnet.segment.PersonMask`).
        world: (T, 33, 3) metres around the hips, BlazePose axes (x right, y down, z away).
        masks: the T person masks of (H, W) as :class:`PackedMasks` (empty where not found), or None;
            a (T, H, W) tensor in {0, 1} given here is packed (above 0.5 is the person).
        found: (T,) bool, whether the person was found in the frame.
        size: (H, W).
    """

    landmarks: torch.Tensor
    world: torch.Tensor
    masks: PackedMasks | None
    found: torch.Tensor
    size: tuple[int, int]

    def __post_init__(self) -> None:
        d = check_shape(self.landmarks, ["T", _N, 5], name="landmarks")
        check_shape(self.world, [d["T"], _N, 3], name="world")
        check_shape(self.found, [d["T"]], name="found")
        if isinstance(self.masks, torch.Tensor):
            check_shape(self.masks, [d["T"], int(self.size[0]), int(self.size[1])], name="masks")
            object.__setattr__(self, "masks", PackedMasks.from_masks(self.masks))
        elif self.masks is not None and (len(self.masks) != d["T"] or self.masks.size != tuple(self.size)):
            raise ShapeError(f"masks: expected {d['T']} masks of {tuple(self.size)}, got {len(self.masks)} of "
                             f"{self.masks.size}")

    @property
    def n_frames(self) -> int:
        return self.landmarks.shape[0]

    def slice(self, start: int, stop: int) -> Observations:
        """Frames [start, stop)."""
        m = None if self.masks is None else self.masks[start:stop]
        return replace(self, landmarks=self.landmarks[start:stop], world=self.world[start:stop], masks=m,
                       found=self.found[start:stop])


def world_to_view_axes(world: torch.Tensor) -> torch.Tensor:
    """BlazePose world axes (x right, y down, z away) → view axes (x right, y up, z toward the camera)."""
    check_shape(world, ["...", 3], name="world")
    return world * world.new_tensor([1.0, -1.0, -1.0])


def fill_missing(obs: Observations, name: str = "video") -> Observations:
    """Interpolate landmarks (linearly; held at the ends) over frames where no person was found.

    Their visibility is halved, so they weigh less. Raises :class:`InputError` when no frame has a person.
    """
    found = obs.found.bool()
    if not bool(found.any()):
        raise InputError(f"{name}: no person found in any frame (expected a photo or video showing a person)")
    if bool(found.all()):
        return obs
    t = torch.arange(obs.n_frames, dtype=torch.float64)
    have = t[found]
    lm, wd = obs.landmarks.clone(), obs.world.clone()
    for i in torch.nonzero(~found).flatten().tolist():
        j = int(torch.searchsorted(have, torch.tensor(float(i))))
        a, b = have[max(j - 1, 0)], have[min(j, len(have) - 1)]
        u = 0.0 if a == b else float((i - a) / (b - a))
        for arr in (lm, wd):
            arr[i] = (1 - u) * arr[int(a)] + u * arr[int(b)]
        lm[i, :, 3:] *= 0.5
    return replace(obs, landmarks=lm, world=wd)


def observe_frames(frames: Iterable[torch.Tensor], models=None, name: str = "video",
                   window: int | None = 8) -> Observations:
    """Segment the largest person in each (3, H, W) sRGB frame and collect the evidence.

    ``window`` is the fit's (:func:`relightnet.fit.fit_observations`): each complete window's masks are
    kept at its working resolution (:class:`PackedMasks`), exactly the masks the fit's silhouette term
    resamples them to; None keeps them at the frames' size. A fit with another window resamples them again.

    Raises:
        InputError: ``"{name}: no person found ..."`` when no frame shows a person.
    """
    from ..segment.video import track_person

    lms, wds, masks, found = [], [], None, []
    for frame, res in track_person(frames, models, name=name):
        if masks is None:
            masks = PackedMasks(tuple(frame.shape[1:]), window)
        if res is None:
            lms.append(torch.zeros(_N, 5))
            wds.append(torch.zeros(_N, 3))
            masks.append_empty()
            found.append(False)
        else:
            lms.append(res.landmarks[:_N].float())
            wds.append(res.world[:_N].float())
            masks.append(res.mask > 0.5)
            found.append(True)
    if masks is None:
        raise InputError(f"{name}: no frames")
    obs = Observations(torch.stack(lms), torch.stack(wds), masks, torch.tensor(found), masks.size)
    return fill_missing(obs, name)
