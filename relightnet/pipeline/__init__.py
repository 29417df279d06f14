"""Whole jobs: relight an image (2D path) and the demo. relight-video, avatar and compare are still to come."""

from .demo import run_demo
from .relight_image import RelitImage, match_exposure, relight_image

__all__ = ["run_demo", "RelitImage", "match_exposure", "relight_image"]
