"""Spherical harmonics, the maths of a light: the basis, frames, direction sets, projection between
environment maps and SH, irradiance and the cosine lobe, rotation, light metrics, the light solve, and
the light files (:func:`load_light_file`, :func:`save_light`, light sequences).

Conventions are those of docs/design.md ("Conventions"): real orthonormal SH without the
Condon–Shortley phase, k = l(l+1)+m, directions in the light frame. A light as a user gives it (in
words, a preset name, a plate) is :mod:`relightnet.light`, the floor above.
"""

from .basis import SHBasis, sh_basis, sh_count, sh_index
from .directions import directions_to_latlong, fibonacci_sphere, latlong_directions
from .frames import camera_normals_to_light, light_to_world, world_to_light
from .io import load_light_file, load_light_sequence, resize_sh, save_light, save_light_sequence
from .irradiance import Irradiance, cone_transport, cosine_lobe, irradiance
from .light_solve import Evidence, light_evidence, pool_evidence, solve_light
from .metrics import direction_error, dominant_direction, scale_invariant_light_error
from .projection import project, project_envmap, radiance, sh_to_envmap
from .rotation import RotateSH, rotate_sh, rotate_sh_up

__all__ = [
    "sh_basis", "SHBasis", "sh_count", "sh_index", "world_to_light", "light_to_world", "camera_normals_to_light",
    "fibonacci_sphere", "latlong_directions", "directions_to_latlong", "irradiance", "Irradiance", "cosine_lobe",
    "cone_transport",
    "project", "project_envmap", "sh_to_envmap", "radiance", "rotate_sh", "RotateSH", "rotate_sh_up", "solve_light",
    "light_evidence", "pool_evidence", "Evidence", "scale_invariant_light_error", "direction_error",
    "dominant_direction", "save_light", "load_light_file", "save_light_sequence", "load_light_sequence", "resize_sh",
]
