"""File I/O: atomic writes, 8-bit images (PNG, JPEG, WebP), HDR environment maps (EXR/HDR), videos (PyAV).

Every writer goes through :func:`atomic_write`, so an interrupted run never
leaves a truncated file behind.

The public names are the readers and writers of each kind of file (images and masks, environment
maps, videos and their :class:`VideoInfo`, a side-by-side video) and the photo suffixes; the
limits, probes, mask videos and the restricted unpickler stay in their modules.

The names below are loaded from their modules on first use, so that the torch-free parts
(:mod:`.probe`, :mod:`.limits`) can refuse an oversized file before torch is imported."""

from ..lazy import lazy_package

#: Where each public name lives (loaded on first access, :func:`relightnet.lazy.lazy_package`).
_WHERE = {
    "atomic_write": "atomic", "read_image": "image", "write_image": "image", "read_image_alpha": "image",
    "read_mask": "image", "to_uint8": "image", "read_envmap": "envmap", "write_envmap": "envmap", "read_video": "video",
    "VideoWriter": "video", "video_info": "video", "VideoInfo": "video", "count_frames": "video",
    "PHOTO_SUFFIXES": "probe", "write_side_by_side": "side_by_side",
}

__all__ = lazy_package(__name__, _WHERE)
