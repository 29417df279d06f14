"""Person masks and body landmarks from real photos and videos, with the shipped models.

Two MediaPipe models (Apache-2.0; ``relightnet/weights/NOTICE``) converted to ONNX and run by
ONNX Runtime: the selfie segmentation model finds the person's box in the whole frame, the
full-body pose model segments a square crop around it and gives 33 landmarks
(:mod:`.person`); in a video the crop follows the previous frame's mask (:mod:`.video`) and the
mask is held steady over time along the landmarks' motion (:mod:`.steady`).
:mod:`.sources` holds the rule by which every command picks a person mask; :mod:`.jobs` the
``segment`` job (masks and landmarks of photos and videos, written out).

Example:
    >>> from relightnet.segment import segment_person  # doctest: +SKIP
    >>> res = segment_person(image)  # image (3, H, W) sRGB in [0, 1]  # doctest: +SKIP
    >>> res.mask.shape, res.landmarks.shape  # (H, W), (33, 5)  # doctest: +SKIP
"""

from .jobs import MASK_VIDEO_SUFFIXES, save_landmarks, segment_files
from .matte import BAND_FRACTION, MIN_BAND, SoftMatte, band_radius, border_band, soft_matte
from .models import INPUT_SIZE, LANDMARK_NAMES, POSE_FILE, SELFIE_FILE, PersonModels, PoseOutput
from .person import (
    CROP_SCALE,
    PersonMask,
    candidate_crops,
    crop_around,
    find_person,
    mask_box,
    refine_person,
    segment_crop,
    segment_person,
)
from .sources import MASK_SOURCES, check_mask_source, person_mask, video_masks
from .steady import STEADY_MARGIN
from .video import PersonTracker, track_person

__all__ = [
    "MASK_VIDEO_SUFFIXES", "save_landmarks", "segment_files",
    "BAND_FRACTION", "MIN_BAND", "SoftMatte", "band_radius", "border_band", "soft_matte",
    "INPUT_SIZE", "LANDMARK_NAMES", "POSE_FILE", "SELFIE_FILE", "PersonModels", "PoseOutput",
    "CROP_SCALE", "PersonMask", "candidate_crops", "crop_around", "find_person", "mask_box", "refine_person",
    "segment_crop", "segment_person",
    "MASK_SOURCES", "check_mask_source", "person_mask", "video_masks",
    "STEADY_MARGIN", "PersonTracker", "track_person",
]
