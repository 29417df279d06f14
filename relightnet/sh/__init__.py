"""Spherical harmonics: basis, frames, direction sets, projection, irradiance, rotation, light I/O,
the light solve.

Conventions are those of docs/design.md ("Conventions"): real orthonormal SH without the
Condon–Shortley phase, k = l(l+1)+m, directions in the light frame.
"""

from .basis import SHBasis, sh_basis, sh_count, sh_degrees, sh_index
from .directions import (
    directions_to_latlong,
    fibonacci_hemisphere,
    fibonacci_sphere,
    latlong_directions,
    random_fibonacci_sphere,
)
from .frames import (
    WORLD_TO_LIGHT,
    camera_normals_to_light,
    light_to_world,
    rotation_world_to_light,
    world_to_light,
)
from .io import LIGHT_SUFFIXES, load_light, load_light_sequence, resize_sh, save_light, save_light_sequence
from .irradiance import Irradiance, cone_band_factors, cone_transport, cosine_lobe, cosine_lobe_per_coeff, irradiance
from .light_solve import Evidence, light_evidence, pool_evidence, solve_light, spd_solve, stack_evidence
from .metrics import (
    chromaticity_error,
    direction_error,
    dominant_direction,
    irradiance_samples,
    scale_invariant_light_error,
)
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
from .projection import project, project_envmap, radiance, sh_to_envmap
from .rotation import RotateSH, rotate_sh, rotate_sh_up, rotation_about_up, sh_rotation_matrix
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
    "SHBasis", "sh_basis", "sh_count", "sh_degrees", "sh_index",
    "directions_to_latlong", "fibonacci_hemisphere", "fibonacci_sphere", "latlong_directions",
    "random_fibonacci_sphere",
    "WORLD_TO_LIGHT", "camera_normals_to_light", "light_to_world", "rotation_world_to_light",
    "world_to_light",
    "Irradiance", "cone_band_factors", "cone_transport", "cosine_lobe", "cosine_lobe_per_coeff", "irradiance",
    "Evidence", "light_evidence", "pool_evidence", "solve_light", "spd_solve", "stack_evidence",
    "project", "project_envmap", "radiance", "sh_to_envmap",
    "chromaticity_error", "direction_error", "dominant_direction", "irradiance_samples", "scale_invariant_light_error",
    "RotateSH", "rotate_sh", "rotate_sh_up", "rotation_about_up", "sh_rotation_matrix",
    "LIGHT_SUFFIXES", "load_light", "resize_sh", "save_light", "load_light_sequence", "save_light_sequence",
    "ambient_light", "directional_light", "preset_envmap", "preset_light", "preset_names", "preset_path", "side_light",
    "auto_exposure", "light_preview", "render_presets", "render_sphere", "sphere_normals",
    "camera_direction", "disc_band_factors", "disc_light", "is_light_words", "light_from_words",
    "parse_light_words", "words_envmap",
    "DEFAULT_HFOV", "SEEN_FADE_DEG", "Plate", "PlateView", "combine_person_plate", "load_plate", "load_plate_light",
    "plate_envmap", "plate_light", "plate_seen", "plate_view",
]
