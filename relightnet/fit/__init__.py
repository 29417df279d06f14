"""Fit the Anny body to a person in a photo or a video (motion capture from landmarks and masks).

The evidence (:class:`Observations`: BlazePose's 33 landmarks in pixels and metres, the person
mask, kept packed: :class:`~relightnet.fit.masks.PackedMasks`) comes from :mod:`relightnet.segment`
(:func:`observe_frames`); :data:`~relightnet.fit.landmarks.LANDMARK_SOURCES` is the one correspondence
between those landmarks and Anny's points. :func:`fit_observations` fits the bones of
:data:`~relightnet.fit.body_model.FIT_BONES`, the global orientation and translation and (optionally)
the shape; :func:`smooth_motion` smooths a video's track and
:func:`~relightnet.fit.smooth.place_in_world` turns it into an Anny motion file's content;
:func:`retarget_motion` hands it to another body; :func:`fit_file` does it all for a photo or video
file; :mod:`.metrics` measures a fit against the truth.

The public names are those steps, their options and results (:class:`FitOptions`, :class:`FitWeights`,
:class:`FitResult`, :class:`FitOutput`, :class:`FitBody`), the camera intrinsics a fit starts from and
the fit metrics; the terms, priors, initialisation and previews stay in their modules.

Example:
    >>> from relightnet.fit import fit_file  # doctest: +SKIP
    >>> out = fit_file("walk.mp4")  # doctest: +SKIP
    >>> out.motion.pose.shape  # (T, 104, 3)  # doctest: +SKIP
"""

from .body_model import FitBody
from .camera import default_intrinsics, exif_intrinsics
from .job import FitOptions, FitOutput, fit_file
from .metrics import acceleration_error, foot_skating, landmark_error, mask_iou, mpjpe, pa_mpjpe
from .observe import Observations, observe_frames
from .retarget import retarget_motion, to_default_avatar
from .smooth import smooth_motion
from .solve import FitResult, FitWeights, fit_observations

__all__ = [
    "FitBody", "FitOptions", "FitOutput", "FitResult", "FitWeights", "fit_file", "fit_observations", "observe_frames",
    "Observations", "smooth_motion", "retarget_motion", "to_default_avatar", "default_intrinsics", "exif_intrinsics",
    "mpjpe", "pa_mpjpe", "mask_iou", "landmark_error", "foot_skating", "acceleration_error",
]
