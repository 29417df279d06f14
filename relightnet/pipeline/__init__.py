"""Whole jobs: the demo (relight-image, relight-video, avatar and compare come with the pipeline issue)."""

from .demo import run_demo

__all__ = ["run_demo"]
