"""File I/O: atomic writes, 8-bit images (PNG), HDR environment maps (EXR/HDR), videos (PyAV).

Every writer goes through :func:`atomic_write`, so an interrupted run never
leaves a truncated file behind.
"""

from .atomic import atomic_write
from .envmap import ENVMAP_SUFFIXES, read_envmap, write_envmap
from .image import (
    linear_to_srgb,
    read_alpha,
    read_image,
    read_image_alpha,
    read_mask,
    srgb_to_linear,
    to_uint8,
    write_image,
)
from .video import VideoInfo, VideoWriter, count_frames, frames_with_masks, read_masks, read_video, video_info

__all__ = [
    "atomic_write",
    "ENVMAP_SUFFIXES", "read_envmap", "write_envmap",
    "linear_to_srgb", "srgb_to_linear", "to_uint8", "read_image", "read_image_alpha", "read_alpha", "read_mask",
    "write_image",
    "VideoInfo", "VideoWriter", "count_frames", "frames_with_masks", "read_masks", "read_video", "video_info",
]
