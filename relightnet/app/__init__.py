"""The local web app (``relightnet app``, the optional extra ``relightnet[app]``: Gradio).

A photo's CNN prediction is kept (:class:`RelightSession`, of a :class:`Photo` from :func:`load_photo`)
and every change of light only re-shades it; the page (:func:`build_app`) is served on 127.0.0.1 only
(:func:`launch`). These are the public names; the controls and the server's parts stay in their modules.
Importing this package does not import Gradio; :func:`build_app` and :func:`launch` do."""

from .server import launch
from .session import Photo, RelightSession, load_photo
from .ui import build_app

__all__ = [
    "launch", "build_app", "RelightSession", "Photo", "load_photo",
]
