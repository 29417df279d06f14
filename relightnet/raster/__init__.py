"""Pure-torch rasterization: cameras, ``rasterize`` → ``Fragments``, ``interpolate``, ``texture``.

The public names are what a renderer needs: the cameras (:class:`Camera`, :func:`default_camera`,
:func:`look_at`, :func:`perspective_camera`, :func:`orthographic_camera`), the primitives with complete
contracts (:func:`rasterize` → :class:`Fragments`, :func:`interpolate`, :func:`texture`,
:func:`antialias`), a :class:`Window` of the frame (e.g. a mesh's :func:`screen_box`, rasterized on its
own: the same fragments as the whole frame's at its pixels, every buffer its size), the layout
conversions and the mask morphology (:func:`erode`, :func:`dilate`). The per-pixel forms and the
projection helpers other floors use stay in their modules (:mod:`.camera`, :mod:`.interpolate`,
:mod:`.texture`, :mod:`.antialias`, :mod:`.morphology`).

Conventions (OpenGL; details in :mod:`relightnet.raster.camera`): the camera looks
along −z with +y up, pixel (0, 0) is the top-left pixel and pixel centres sit at
+0.5. Rasterizer outputs are channels-last (B, H, W, C); :func:`to_channels_first`
and :func:`to_channels_last` convert to and from the CNN layout (B, C, H, W).
Texture coordinates have v = 0 at the bottom of the image (:mod:`.texture`).
"""

from .antialias import antialias
from .camera import Camera, default_camera, look_at, orthographic_camera, perspective_camera
from .fragments import Fragments
from .interpolate import Interpolate, interpolate, to_channels_first, to_channels_last
from .morphology import dilate, erode
from .rasterize import rasterize, screen_box
from .texture import texture
from .window import Window

__all__ = [
    "Camera", "default_camera", "look_at", "perspective_camera", "orthographic_camera", "Fragments", "rasterize",
    "Window", "screen_box", "interpolate", "Interpolate", "to_channels_first", "to_channels_last", "texture",
    "antialias", "erode", "dilate",
]
