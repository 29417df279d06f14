"""Lights as a user gives them: in words, by preset name, from a background plate, or from a file
(:func:`load_light`), and pictures of them.

The maths of a light (the SH basis, frames, projection, irradiance, rotation, the light solve) and the
light files are :mod:`relightnet.sh`, the floor below.
"""

from .load import load_light
from .plate import (
    DEFAULT_HFOV,
    SEEN_FADE_DEG,
    Plate,
    PlateView,
    combine_person_plate,
    load_plate,
    load_plate_light,
    plate_envmap,
    plate_light,
    plate_seen,
    plate_view,
)
from .presets import (
    ambient_light,
    directional_light,
    preset_envmap,
    preset_light,
    preset_names,
    preset_path,
    side_light,
)
from .visualize import auto_exposure, light_preview, render_presets, render_sphere, sphere_normals
from .words import (
    camera_direction,
    disc_band_factors,
    disc_light,
    is_light_words,
    light_from_words,
    parse_light_words,
    words_envmap,
)

__all__ = [
    "load_light",
    "ambient_light", "directional_light", "preset_envmap", "preset_light", "preset_names", "preset_path", "side_light",
    "auto_exposure", "light_preview", "render_presets", "render_sphere", "sphere_normals",
    "camera_direction", "disc_band_factors", "disc_light", "is_light_words", "light_from_words",
    "parse_light_words", "words_envmap",
    "DEFAULT_HFOV", "SEEN_FADE_DEG", "Plate", "PlateView", "combine_person_plate", "load_plate", "load_plate_light",
    "plate_envmap", "plate_light", "plate_seen", "plate_view",
]
