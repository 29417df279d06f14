"""Person masks and body landmarks from real photos and videos, with the shipped models.

Two MediaPipe models (Apache-2.0; ``relightnet/weights/NOTICE``) converted to ONNX and run by
ONNX Runtime: the selfie segmentation model finds the person's box in the whole frame, the
full-body pose model segments a square crop around it and gives 33 landmarks
(:mod:`.person`); in a video the crop follows the previous frame's mask (:mod:`.video`) and the
mask is held steady over time along the landmarks' motion (:mod:`.steady`).
:mod:`.sources` holds the rule by which every command picks a person mask; :mod:`.jobs` the
``segment`` job (masks and landmarks of photos and videos, written out).

The public names are those entry points: a photo's mask and landmarks (:func:`segment_person` →
:class:`PersonMask`, with :class:`PersonModels` loaded once), a video's (:func:`track_person`,
:class:`PersonTracker`), the mask a command uses (:func:`person_mask`, :func:`video_masks`), the
``segment`` job (:func:`segment_files`), the soft matte of the border band (:func:`soft_matte`) and
the landmark names. The crops, the matte's parts and the models' files stay in their modules.

Example:
    >>> from relightnet.segment import segment_person  # doctest: +SKIP
    >>> res = segment_person(image)  # image (3, H, W) sRGB in [0, 1]  # doctest: +SKIP
    >>> res.mask.shape, res.landmarks.shape  # (H, W), (33, 5)  # doctest: +SKIP
"""

from .jobs import segment_files
from .matte import soft_matte
from .models import LANDMARK_NAMES, PersonModels
from .person import PersonMask, segment_person
from .sources import person_mask, video_masks
from .video import PersonTracker, track_person

__all__ = [
    "segment_person", "PersonMask", "PersonModels", "soft_matte", "segment_files", "person_mask", "video_masks",
    "track_person", "PersonTracker", "LANDMARK_NAMES",
]
