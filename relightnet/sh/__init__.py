"""Spherical harmonics, the maths of a light: the basis, frames, direction sets, projection between
environment maps and SH, irradiance and the cosine lobe, rotation, light metrics, the light solve, and
the light files (:func:`load_light_file`, :func:`save_light`, light sequences).

Conventions are those of docs/design.md ("Conventions"): real orthonormal SH without the
Condon–Shortley phase, k = l(l+1)+m, directions in the light frame. A light as a user gives it (in
words, a preset name, a plate) is :mod:`relightnet.light`, the floor above.
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
from .io import LIGHT_SUFFIXES, load_light_file, load_light_sequence, resize_sh, save_light, save_light_sequence
from .irradiance import Irradiance, cone_band_factors, cone_transport, cosine_lobe, cosine_lobe_per_coeff, irradiance
from .light_solve import Evidence, light_evidence, pool_evidence, solve_light, spd_solve, stack_evidence
from .metrics import (
    chromaticity_error,
    direction_error,
    dominant_direction,
    irradiance_samples,
    scale_invariant_light_error,
)
from .projection import project, project_envmap, radiance, sh_to_envmap
from .rotation import RotateSH, rotate_sh, rotate_sh_up, rotation_about_up, sh_rotation_matrix

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
    "LIGHT_SUFFIXES", "load_light_file", "resize_sh", "save_light", "load_light_sequence", "save_light_sequence",
]
