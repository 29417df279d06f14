"""Whole jobs: relight an image or a video (2D path), put a relit avatar into a video (3D path),
compare the 2D and 3D paths against ground truth, check the 2D path on real photos, the demo; the
dressed avatar, its default albedo's smooth garment edges, and the clean plate that lets the avatar
take the target person's place (with the check that the target's camera is fixed)."""

from .avatar import AvatarResult, avatar
from .backends import BACKENDS, OnnxPredictor, Predictor, TorchPredictor, as_predictor, make_predictor
from .camera_motion import (
    EARLY_FRAMES,
    MOTION_SHARE,
    THUMB_SIDE,
    Thumbnail,
    check_fixed_camera,
    phase_shift,
    shifts_to_first,
    thumbnail,
)
from .clean_plate import (
    CleanPlate,
    Placement,
    check_camera_start,
    check_stand_in,
    clean_plate,
    person_placement,
    placed_camera,
    plate_psnr,
    stand_in,
    stand_in_frames,
)
from .compare import ClipOutputs, CompareResult, clip_metrics, compare, compare_clip, source_light
from .demo import run_demo
from .outfits import OUTFIT_COLORS, OUTFIT_SLOTS, DressedBody, OutfitDraw, avatar_look, draw_outfit, dressed_body
from .photo_checks import format_photo_report, photo_checks, write_photo_report
from .relight_bands import BandRelit, relight_over_photo
from .relight_image import Relit, RelitImage, match_exposure, over_photo, relight_image, relight_prediction
from .relight_video import relight_video
from .scene import avatar_albedo, load_body, load_camera, motion_params, open_motion
from .smooth_albedo import boundary_jaggedness, smooth_default_albedo
from .video_lights import estimate_video_evidence, estimate_video_lights
from .walk_target import WalkingTarget, walking_target

__all__ = [
    "AvatarResult", "avatar", "estimate_video_evidence", "estimate_video_lights",
    "BACKENDS", "OnnxPredictor", "Predictor", "TorchPredictor", "as_predictor", "make_predictor",
    "ClipOutputs", "CompareResult", "clip_metrics", "compare", "compare_clip", "source_light",
    "run_demo", "Relit", "RelitImage", "match_exposure", "over_photo", "relight_image", "relight_prediction",
    "relight_video", "BandRelit", "relight_over_photo",
    "avatar_albedo", "load_body", "load_camera", "motion_params", "open_motion",
    "CleanPlate", "Placement", "clean_plate", "person_placement", "placed_camera", "plate_psnr", "stand_in",
    "check_stand_in", "check_camera_start", "stand_in_frames", "avatar_look",
    "EARLY_FRAMES", "MOTION_SHARE", "THUMB_SIDE", "Thumbnail", "check_fixed_camera", "phase_shift", "shifts_to_first",
    "thumbnail",
    "OUTFIT_COLORS", "OUTFIT_SLOTS", "DressedBody", "OutfitDraw", "draw_outfit", "dressed_body",
    "boundary_jaggedness", "smooth_default_albedo", "WalkingTarget", "walking_target",
    "format_photo_report", "photo_checks", "write_photo_report",
]
