"""Whole jobs: relight an image or a video (2D path) and the demo. avatar and compare are still to come."""

from .demo import run_demo
from .relight_image import RelitImage, match_exposure, relight_image
from .relight_video import relight_video

__all__ = ["run_demo", "RelitImage", "match_exposure", "relight_image", "relight_video"]
