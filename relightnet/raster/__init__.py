"""Pure-torch rasterization: cameras, ``rasterize`` → ``Fragments``, ``interpolate``, ``texture``.

A :class:`Window` of the frame (e.g. a mesh's :func:`screen_box`) is rasterized on its own, the
same fragments as the whole frame's at its pixels, every buffer its size.

Conventions (OpenGL; details in :mod:`relightnet.raster.camera`): the camera looks
along −z with +y up, pixel (0, 0) is the top-left pixel and pixel centres sit at
+0.5. Rasterizer outputs are channels-last (B, H, W, C); :func:`to_channels_first`
and :func:`to_channels_last` convert to and from the CNN layout (B, C, H, W).
Texture coordinates have v = 0 at the bottom of the image (:mod:`.texture`).
"""

from .antialias import antialias, antialias_pixels, silhouette_pixels
from .camera import (
    Camera,
    default_camera,
    fov_projection,
    look_at,
    ndc_to_pixel,
    orthographic_camera,
    orthographic_projection,
    perspective_camera,
    perspective_projection,
    pixel_to_ndc,
)
from .fragments import Fragments
from .interpolate import Interpolate, interpolate, interpolate_pixels, to_channels_first, to_channels_last
from .morphology import box_filter, dilate, erode
from .rasterize import rasterize, screen_box
from .texture import texture, texture_pixels
from .window import Window

__all__ = [
    "Camera", "default_camera", "fov_projection", "look_at", "ndc_to_pixel", "orthographic_camera",
    "orthographic_projection", "perspective_camera", "perspective_projection", "pixel_to_ndc",
    "Fragments", "rasterize", "screen_box", "Window",
    "interpolate", "interpolate_pixels", "Interpolate", "to_channels_first", "to_channels_last",
    "texture", "texture_pixels", "antialias", "antialias_pixels", "silhouette_pixels", "erode", "dilate", "box_filter",
]
