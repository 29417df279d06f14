"""Whole jobs: relight an image or a video (2D path), put a relit avatar into a video (3D path),
compare the 2D and 3D paths against ground truth, check the 2D path on real photos, the demo; the
dressed avatar, its default albedo's smooth garment edges, and the clean plate that lets the avatar
take the target person's place (with the check that the target's camera is fixed).

The public names are those jobs (:func:`relight_image`, :func:`relight_video`, :func:`relight_over_photo`
→ :class:`RelitPhoto`, :func:`avatar` → :class:`AvatarResult`, :func:`compare`, :func:`compare_clip`,
:func:`photo_checks`, :func:`clean_plate`, :func:`run_demo`, :func:`walking_target`), their settings
(:class:`AvatarLook`, :class:`AvatarPlacement`, :class:`VideoLightSettings`, :class:`PredictorSettings`),
the predictors that run the CNN (:func:`make_predictor`, :class:`TorchPredictor`, :class:`OnnxPredictor`)
and the light estimate of a video; the jobs' parts (the scene, the outfits, the camera-motion check,
the clean plate's stand-in) stay in their modules.

The names are loaded on first use (PEP 562): a job imports only the modules it runs, so
``relight-image`` does not pay for the avatar's renderer and ray tracer at start-up."""

from __future__ import annotations

from ..lazy import lazy_package

#: public name → the module of this package that defines it
_EXPORTS = {
    "avatar": "avatar", "AvatarResult": "avatar", "AvatarLook": "settings", "AvatarPlacement": "settings",
    "VideoLightSettings": "settings", "PredictorSettings": "settings", "relight_image": "relight_image",
    "relight_video": "relight_video", "relight_over_photo": "relight_bands", "RelitPhoto": "relight_bands",
    "compare": "compare", "CompareResult": "compare", "compare_clip": "compare", "photo_checks": "photo_checks",
    "clean_plate": "clean_plate", "CleanPlate": "clean_plate", "run_demo": "demo", "Predictor": "backends",
    "TorchPredictor": "backends", "OnnxPredictor": "backends", "make_predictor": "backends", "BACKENDS": "backends",
    "estimate_video_lights": "video_lights", "walking_target": "walk_target", "WalkingTarget": "walk_target",
}

__all__ = lazy_package(__name__, _EXPORTS)
