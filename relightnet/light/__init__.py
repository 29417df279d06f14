"""Lights as a user gives them: in words, by preset name, from a background plate, or from a file
(:func:`load_light`), and pictures of them.

The maths of a light (the SH basis, frames, projection, irradiance, rotation, the light solve) and the
light files are :mod:`relightnet.sh`, the floor below.
"""

from .load import load_light
from .plate import Plate, combine_person_plate, load_plate, plate_envmap, plate_light, plate_seen
from .presets import ambient_light, directional_light, preset_envmap, preset_light, preset_names, side_light
from .visualize import light_preview, render_presets, render_sphere
from .words import light_from_words, words_envmap

__all__ = [
    "load_light", "preset_light", "preset_names", "preset_envmap", "ambient_light", "directional_light", "side_light",
    "light_from_words", "words_envmap", "Plate", "load_plate", "plate_light", "plate_envmap", "combine_person_plate",
    "plate_seen", "render_sphere", "light_preview", "render_presets",
]
