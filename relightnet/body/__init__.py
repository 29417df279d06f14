"""Body models behind one interface (Anny by default, user-supplied SMPL files), motion, albedo.

Every model is called as ``model(params) -> BodyOutput`` (verts, faces, uv, uv_faces,
normals, joints) in relightnet's world frame: y up, the person facing +z, feet of the
rest pose on y = 0 by default.
"""

from .albedo import default_albedo
from .anny_model import PHENOTYPES, POSE_PRESETS, AnnyBody, pose_preset
from .anny_motion import AnnyMotion, load_anny_motion, save_anny_motion
from .base import BodyModel, BodyOutput
from .garments import RingShape, ring_surface, shell_surface
from .motion import MOTION_KINDS, make_motion
from .motion_io import Motion, load_motion, save_motion
from .smpl_model import SMPLBody

__all__ = [
    "BodyModel", "BodyOutput", "AnnyBody", "SMPLBody", "PHENOTYPES", "POSE_PRESETS", "pose_preset", "make_motion",
    "MOTION_KINDS", "Motion", "load_motion", "save_motion", "AnnyMotion", "load_anny_motion", "save_anny_motion",
    "default_albedo", "RingShape", "shell_surface", "ring_surface",
]
