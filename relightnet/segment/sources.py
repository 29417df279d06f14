"""Where a command's person mask comes from: the one rule every photo and video command follows.

1. a mask the user gives (``--mask`` / ``--masks`` / ``--target-masks``);
2. else a photo's own alpha channel (a cut-out);
3. else ``source="segment"`` (the default): the shipped person segmentation (:mod:`relightnet.segment`);
   ``source="head"``: None, i.e. the CNN's own mask head finds the person.
"""

from __future__ import annotations

import logging

import torch

from ..checks import InputError
from ..names import MASK_SOURCES
from .models import PersonModels
from .person import segment_person
from .video import track_person

logger = logging.getLogger(__name__)

__all__ = ["MASK_SOURCES", "check_mask_source", "person_mask", "video_masks"]



def check_mask_source(source: str) -> str:
    """``source`` if it is one of :data:`MASK_SOURCES`, else an InputError listing them."""
    if source not in MASK_SOURCES:
        raise InputError(f"mask source: expected one of {', '.join(MASK_SOURCES)}, got {source!r}")
    return source


def person_mask(image: torch.Tensor, mask: torch.Tensor | None = None, alpha: torch.Tensor | None = None,
                source: str = "segment", name: str = "image", models: PersonModels | None = None,
                ) -> torch.Tensor | None:
    """A photo's person mask by the rule above.

    Args:
        image: (3, H, W) sRGB in [0, 1].
        mask: (H, W) mask the user gave, or None.
        alpha: (H, W) the photo's alpha in [0, 1], or None.
        source: ``segment`` or ``head`` (used only without mask and alpha).
        name: the photo's name for messages.

    Returns:
        (H, W) float mask in {0, 1}, or None for the CNN's mask head.

    Raises:
        InputError: no person found by the segmentation.
    """
    check_mask_source(source)
    if mask is not None:
        return mask
    if alpha is not None:
        logger.info("no mask given: using the alpha channel of %s as the person's mask", name)
        return (alpha > 0.5).float()
    if source == "head":
        logger.info("no mask given: the model's mask head finds the person in %s", name)
        return None
    logger.info("no mask given: the person segmentation finds the person in %s", name)
    return segment_person(image, models, name=name).mask


def _mask_of(img: torch.Tensor, res) -> torch.Tensor:
    return torch.zeros(img.shape[1:]) if res is None else res.mask


def video_masks(video, masks=None, source: str = "segment", allow_empty: bool = False,
                models: PersonModels | None = None):
    """A video's frames with their person masks by the rule above (streaming).

    Args:
        video: the video file.
        masks: a folder of mask images or a mask video (:func:`relightnet.io.video_masks.frames_with_masks`), or None.
        source: without ``masks``: ``segment`` (the person segmentation, tracked from frame to
            frame) or ``head`` (masks are None: the CNN's mask head).
        allow_empty: pass frames without the person on with an empty mask instead of failing.

    Returns:
        (:class:`~relightnet.io.VideoInfo`, frame count (counted from the packets, :func:`~relightnet.io.count_frames`),
        iterator of (t, frame (3, H, W) float sRGB in [0, 1], mask (H, W) or None)).
        The iterator raises :class:`InputError` naming the frame when a mask is empty (or no
        person is found) and ``allow_empty`` is False.
    """
    from ..io import count_frames, read_video, video_info
    from ..io.video_masks import frames_with_masks

    check_mask_source(source)
    if masks is not None:
        return frames_with_masks(video, masks, allow_empty=allow_empty)
    info = video_info(video)
    frames = (torch.from_numpy(f).permute(2, 0, 1).float().div_(255) for f in read_video(video))
    if source == "head":
        logger.info("no masks given: the model's mask head finds the person in %s", video)
        return info, count_frames(video), ((t, img, None) for t, img in enumerate(frames))
    logger.info("no masks given: the person segmentation finds the person in %s", video)
    tracked = track_person(frames, models, allow_empty=allow_empty, name=str(video))
    return info, count_frames(video), ((t, img, _mask_of(img, res)) for t, (img, res) in enumerate(tracked))
