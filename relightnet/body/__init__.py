"""Body models behind one interface (Anny by default, user-supplied SMPL files), motion, albedo.

Every model is called as ``model(params) -> BodyOutput`` (verts, faces, uv, uv_faces,
normals, joints) in relightnet's world frame: y up, the person facing +z, feet of the
rest pose on y = 0 by default.

The public names are what a user of a body needs: the models (:class:`BodyModel`, :class:`AnnyBody`,
:class:`SMPLBody`, :class:`BodyOutput`) and their phenotypes and pose presets, motions (:func:`make_motion`,
the SMPL-style and Anny motion files: :func:`load_motion`, :func:`save_motion`, :func:`load_anny_motion`,
:func:`save_anny_motion`), the default albedo and the garment geometry (:class:`RingShape`,
:func:`shell_surface`, :func:`ring_surface`). The rotation helpers, the region and part labels, the
subdivision and the shoes stay in their modules (:mod:`.base`, :mod:`.albedo`, :mod:`.subdivide`,
:mod:`.shoes`, ...).
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
