"""Body models behind one interface (Anny by default, user-supplied SMPL files), motion, albedo.

Every model is called as ``model(params) -> BodyOutput`` (verts, faces, uv, uv_faces,
normals, joints) in relightnet's world frame: y up, the person facing +z, feet of the
rest pose on y = 0 by default.
"""

from .albedo import (
    ANNY_PARTS,
    REGIONS,
    Albedo,
    anny_part_labels,
    default_albedo,
    region_labels,
    skin_color,
    vertex_to_texture,
)
from .anny_model import ANNY_TO_WORLD, PHENOTYPES, POSE_PRESETS, AnnyBody, anny_to_world, load_anny, pose_preset
from .anny_motion import AnnyMotion, is_anny_motion, load_anny_motion, save_anny_motion
from .base import (
    GROUND_MODES,
    BodyModel,
    BodyOutput,
    compose_rotvecs,
    matrix_to_rotvec,
    rotvec_to_matrix,
    vertex_normals,
)
from .garments import GarmentPiece, RingShape, hem_field, iso_clip, radial_directions, ring_surface, shell_surface
from .motion import MOTION_KINDS, make_motion
from .motion_io import Z_UP_TO_Y_UP, Motion, load_motion, reorient_motion, save_motion
from .shoes import SHOE_KINDS, shoe_surface
from .smpl_model import SMPL_JOINT_NAMES, SMPL_KEYS, SMPLBody, load_smpl_file, smpl_to_world, spherical_uv
from .subdivide import SubdividedFaces, midpoint_values, subdivide_faces

__all__ = [
    "BodyModel", "BodyOutput", "GROUND_MODES", "vertex_normals", "rotvec_to_matrix", "matrix_to_rotvec",
    "compose_rotvecs",
    "AnnyBody", "ANNY_TO_WORLD", "anny_to_world", "PHENOTYPES", "POSE_PRESETS", "pose_preset", "load_anny",
    "SMPLBody", "SMPL_KEYS", "SMPL_JOINT_NAMES", "load_smpl_file", "smpl_to_world", "spherical_uv",
    "make_motion", "MOTION_KINDS",
    "Motion", "load_motion", "save_motion", "reorient_motion", "Z_UP_TO_Y_UP",
    "AnnyMotion", "is_anny_motion", "load_anny_motion", "save_anny_motion",
    "REGIONS", "ANNY_PARTS", "Albedo", "anny_part_labels", "region_labels", "skin_color", "default_albedo",
    "vertex_to_texture",
    "GarmentPiece", "RingShape", "shell_surface", "ring_surface", "radial_directions", "hem_field", "iso_clip",
    "SHOE_KINDS", "shoe_surface",
    "SubdividedFaces", "subdivide_faces", "midpoint_values",
]
