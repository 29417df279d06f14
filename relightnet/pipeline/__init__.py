"""Whole jobs: relight an image or a video (2D path), put a relit avatar into a video (3D path),
compare the 2D and 3D paths against ground truth, the demo."""

from .avatar import AvatarResult, avatar
from .backends import BACKENDS, OnnxPredictor, Predictor, TorchPredictor, as_predictor, make_predictor
from .compare import ClipOutputs, CompareResult, clip_metrics, compare, compare_clip, source_light
from .demo import run_demo
from .relight_image import Relit, RelitImage, match_exposure, over_photo, relight_image, relight_prediction
from .relight_video import relight_video
from .scene import avatar_albedo, load_body, load_camera, motion_params, open_motion
from .video_lights import estimate_video_evidence, estimate_video_lights

__all__ = [
    "AvatarResult", "avatar", "estimate_video_evidence", "estimate_video_lights",
    "BACKENDS", "OnnxPredictor", "Predictor", "TorchPredictor", "as_predictor", "make_predictor",
    "ClipOutputs", "CompareResult", "clip_metrics", "compare", "compare_clip", "source_light",
    "run_demo", "Relit", "RelitImage", "match_exposure", "over_photo", "relight_image", "relight_prediction",
    "relight_video",
    "avatar_albedo", "load_body", "load_camera", "motion_params", "open_motion",
]
