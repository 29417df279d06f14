"""Blender bridge: export relightnet scenes to .blend files and render path-traced references with Cycles.

Needs the optional extra ``relightnet[blender]`` (PyPI ``bpy`` 5.0.1, Python 3.11, CPU Cycles);
``bpy`` is imported only when a function needs it. Frames: :mod:`.frames` maps relightnet's
world (y up) to Blender's (z up) in one place. Scale: a relightnet render is π × the Cycles
render of the same scene (:mod:`.cycles`).
"""

from .camera import BlenderCamera, blender_camera
from .cycles import CYCLES_TO_RELIGHTNET, CyclesFrame, configure_cycles, open_blend, render_blend, render_current
from .frames import (
    BLENDER_FROM_WORLD,
    blender_to_world,
    equirect_directions,
    latlong_to_equirect,
    transform_to_blender,
    world_to_blender,
)
from .geometry import MAX_SCENE_FACES, blend_face_count, check_blend_geometry
from .scene import export_body_scene, export_scene
from .settings import CyclesSettings, WorldLightSettings
from .world import WorldLight, envmap_world_image, lift_sh, sh_world_image, world_light

__all__ = [
    "BLENDER_FROM_WORLD", "world_to_blender", "blender_to_world", "transform_to_blender", "equirect_directions",
    "latlong_to_equirect",
    "BlenderCamera", "blender_camera",
    "WorldLight", "world_light", "sh_world_image", "envmap_world_image", "lift_sh",
    "export_scene", "export_body_scene", "CyclesSettings", "WorldLightSettings",
    "CYCLES_TO_RELIGHTNET", "CyclesFrame", "configure_cycles", "open_blend", "render_blend", "render_current",
    "MAX_SCENE_FACES", "blend_face_count", "check_blend_geometry",
]
