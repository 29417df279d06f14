"""The local web app (``relightnet app``, the optional extra ``relightnet[app]``: Gradio).

A photo's CNN prediction is kept (:class:`RelightSession`) and every change of light only
re-shades it; the page (:func:`build_app`) is served on 127.0.0.1 only (:func:`launch`).
Importing this package does not import Gradio; :func:`build_app` and :func:`launch` do.
"""

from .controls import LIGHT_SOURCES, direction_to_sphere_point, light_of, sphere_point_to_direction, words_of
from .examples import example_person
from .server import HOST, app_workdir, launch
from .session import Photo, RelightSession, load_photo
from .ui import build_app

__all__ = [
    "LIGHT_SOURCES", "direction_to_sphere_point", "light_of", "sphere_point_to_direction", "words_of",
    "example_person", "HOST", "app_workdir", "launch", "Photo", "RelightSession", "load_photo", "build_app",
]
