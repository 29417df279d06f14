"""Fit the Anny body to a person in a photo or a video (motion capture from landmarks and masks).

The evidence (:class:`Observations`: BlazePose's 33 landmarks in pixels and metres, the person
mask) comes from :mod:`relightnet.segment`; :data:`LANDMARK_SOURCES` is the one correspondence
between those landmarks and Anny's points. :func:`fit_observations` fits the bones of
:data:`FIT_BONES`, the global orientation and translation and (optionally) the shape;
:func:`smooth_motion` smooths a video's track; :mod:`.metrics` measures a fit against the truth.
"""

from .body_model import SHAPE_NAMES, FitBody, phenotype_from_free
from .camera import DEFAULT_FOV_DEG, default_intrinsics, exif_intrinsics, project_points
from .init import kabsch
from .landmarks import LANDMARK_SOURCES, AnnyLandmarks, landmark_weights
from .observe import Observations, fill_missing, observe_frames, world_to_view_axes
from .prior import FIT_BONES, JOINT_LIMITS, limit_bounds, limit_penalty, rest_penalty
from .solve import FitResult, FitWeights, fit_observations

__all__ = [
    "SHAPE_NAMES", "FitBody", "phenotype_from_free",
    "DEFAULT_FOV_DEG", "default_intrinsics", "exif_intrinsics", "project_points",
    "kabsch",
    "LANDMARK_SOURCES", "AnnyLandmarks", "landmark_weights",
    "Observations", "fill_missing", "observe_frames", "world_to_view_axes",
    "FIT_BONES", "JOINT_LIMITS", "limit_bounds", "limit_penalty", "rest_penalty",
    "FitResult", "FitWeights", "fit_observations",
]
