"""Whole jobs: relight an image or a video (2D path), put a relit avatar into a video (3D path),
compare the 2D and 3D paths against ground truth, check the 2D path on real photos, the demo; the
dressed avatar, its default albedo's smooth garment edges, and the clean plate that lets the avatar
take the target person's place (with the check that the target's camera is fixed).

The names are loaded on first use (PEP 562): a job imports only the modules it runs, so
``relight-image`` does not pay for the avatar's renderer and ray tracer at start-up.
"""

from __future__ import annotations

from ..lazy import lazy_package

#: public name → the module of this package that defines it
_EXPORTS = {
    "AvatarResult": "avatar", "avatar": "avatar",
    "BACKENDS": "backends", "OnnxPredictor": "backends", "Predictor": "backends", "TorchPredictor": "backends",
    "as_predictor": "backends", "make_predictor": "backends",
    "EARLY_FRAMES": "camera_motion", "MOTION_SHARE": "camera_motion", "THUMB_SIDE": "camera_motion",
    "Thumbnail": "camera_motion", "check_fixed_camera": "camera_motion", "phase_shift": "camera_motion",
    "shifts_to_first": "camera_motion", "thumbnail": "camera_motion",
    "CleanPlate": "clean_plate", "Placement": "clean_plate", "check_camera_start": "clean_plate",
    "check_stand_in": "clean_plate", "clean_plate": "clean_plate", "person_placement": "clean_plate",
    "placed_camera": "clean_plate", "plate_psnr": "clean_plate", "stand_in": "clean_plate",
    "stand_in_frames": "clean_plate",
    "ClipOutputs": "compare", "CompareResult": "compare", "clip_metrics": "compare", "compare": "compare",
    "compare_clip": "compare", "source_light": "compare",
    "run_demo": "demo",
    "OUTFIT_COLORS": "outfits", "OUTFIT_SLOTS": "outfits", "DressedBody": "outfits", "OutfitDraw": "outfits",
    "avatar_look": "outfits", "draw_outfit": "outfits", "dressed_body": "outfits",
    "format_photo_report": "photo_checks", "photo_checks": "photo_checks", "write_photo_report": "photo_checks",
    "RelitPhoto": "relight_bands", "relight_over_photo": "relight_bands",
    "match_exposure": "relight_image", "relight_image": "relight_image",
    "relight_video": "relight_video",
    "avatar_albedo": "scene", "load_body": "scene", "load_camera": "scene", "motion_params": "scene",
    "open_motion": "scene",
    "AvatarLook": "settings", "AvatarPlacement": "settings", "PredictorSettings": "settings",
    "VideoLightSettings": "settings",
    "boundary_jaggedness": "smooth_albedo", "smooth_default_albedo": "smooth_albedo",
    "estimate_video_evidence": "video_lights", "estimate_video_lights": "video_lights",
    "WalkingTarget": "walk_target", "walking_target": "walk_target",
}

__all__ = lazy_package(__name__, _EXPORTS)
