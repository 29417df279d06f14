"""Fit the Anny body to a person in a photo or a video (motion capture from landmarks and masks).

The evidence (:class:`Observations`: BlazePose's 33 landmarks in pixels and metres, the person
mask, kept packed: :class:`PackedMasks`) comes from :mod:`relightnet.segment`;
:data:`LANDMARK_SOURCES` is the one correspondence between those landmarks and Anny's points.
:func:`fit_observations` fits the bones of :data:`FIT_BONES`, the global orientation and translation
and (optionally) the shape;
:func:`smooth_motion` smooths a video's track and :func:`place_in_world` turns it into an Anny
motion file's content; :func:`retarget_motion` hands it to another body; :func:`fit_file` does
it all for a photo or video file; :mod:`.metrics` measures a fit against the truth.

Example:
    >>> from relightnet.fit import fit_file  # doctest: +SKIP
    >>> out = fit_file("walk.mp4")  # doctest: +SKIP
    >>> out.motion.pose.shape  # (T, 104, 3)  # doctest: +SKIP
"""

from .body_model import SHAPE_NAMES, FitBody, phenotype_from_free, rest_near
from .camera import DEFAULT_FOV_DEG, default_intrinsics, exif_intrinsics, project_points
from .init import (
                   CORE_SLOTS,
                   MAX_TURN_DEG,
                   TORSO_SLOTS,
                   initial_orientation,
                   initial_translation,
                   kabsch,
                   relative_turn,
)
from .job import (
                  FitOptions,
                  FitOutput,
                  fit_file,
                  media_frames,
                  motion_for_avatar,
                  write_fit_masks,
                  write_preview,
)
from .landmarks import LANDMARK_SOURCES, AnnyLandmarks, landmark_weights
from .masks import MAX_FRAME_BYTES, PackedMasks
from .metrics import acceleration_error, foot_skating, landmark_error, mask_iou, mpjpe, pa_mpjpe
from .observe import Observations, fill_missing, observe_frames, world_to_view_axes
from .preview import CHUNK_PIXELS, chunk_frames, fit_camera, fit_meshes, fit_silhouettes, overlay_frames
from .prior import FIT_BONES, JOINT_LIMITS, limit_bounds, limit_penalty, rest_penalty
from .retarget import leg_length, retarget_motion, to_default_avatar
from .smooth import FOOT_SLOTS, SMOOTH_BLOCK, gaussian_weights, place_in_world, smooth_motion, smooth_rotations
from .solve import MAX_FIT_FRAMES, MAX_WINDOW_PIXELS, FitResult, FitWeights, fit_observations
from .terms import (
                  HIP_SLOTS,
                  SILHOUETTE_HEIGHT,
                  WORK_ASPECT,
                  WORLD_UNIT,
                  SilhouetteTargets,
                  acceleration_term,
                  outline_matches,
                  person_scale,
                  reprojection_term,
                  silhouette_targets,
                  silhouette_term,
                  working_size,
                  world_term,
)

__all__ = [
    "SHAPE_NAMES", "FitBody", "phenotype_from_free", "rest_near",
    "DEFAULT_FOV_DEG", "default_intrinsics", "exif_intrinsics", "project_points",
    "CORE_SLOTS", "MAX_TURN_DEG", "TORSO_SLOTS", "initial_orientation", "initial_translation", "kabsch",
    "relative_turn",
    "FitOptions", "FitOutput", "fit_file", "media_frames", "motion_for_avatar", "write_fit_masks",
    "write_preview",
    "LANDMARK_SOURCES", "AnnyLandmarks", "landmark_weights",
    "acceleration_error", "foot_skating", "landmark_error", "mask_iou", "mpjpe", "pa_mpjpe",
    "MAX_FRAME_BYTES", "PackedMasks", "Observations", "fill_missing", "observe_frames", "world_to_view_axes",
    "CHUNK_PIXELS", "chunk_frames", "fit_camera", "fit_meshes", "fit_silhouettes", "overlay_frames",
    "FIT_BONES", "JOINT_LIMITS", "limit_bounds", "limit_penalty", "rest_penalty",
    "leg_length", "retarget_motion", "to_default_avatar",
    "FOOT_SLOTS", "SMOOTH_BLOCK", "gaussian_weights", "place_in_world", "smooth_motion", "smooth_rotations",
    "MAX_FIT_FRAMES", "MAX_WINDOW_PIXELS", "FitResult", "FitWeights", "fit_observations",
    "HIP_SLOTS", "SILHOUETTE_HEIGHT", "WORK_ASPECT", "WORLD_UNIT", "SilhouetteTargets", "acceleration_term",
    "outline_matches", "person_scale", "reprojection_term", "silhouette_targets", "silhouette_term", "working_size",
    "world_term",
]
