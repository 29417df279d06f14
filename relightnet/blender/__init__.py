"""Blender bridge: export relightnet scenes to .blend files and render path-traced references with Cycles.

The public names are the exports (:func:`export_scene`, :func:`export_body_scene`), the render
(:func:`render_blend`) and their settings (:class:`CyclesSettings`, :class:`WorldLightSettings`), the
world light (:func:`world_light` → :class:`WorldLight`) and the frame conversion
(:func:`world_to_blender`, :func:`blender_to_world`); the camera, geometry and Cycles helpers stay in
their modules.

Needs the optional extra ``relightnet[blender]`` (PyPI ``bpy`` 5.0.1, Python 3.11, CPU Cycles);
``bpy`` is imported only when a function needs it. Frames: :mod:`.frames` maps relightnet's
world (y up) to Blender's (z up) in one place. Scale: a relightnet render is π × the Cycles
render of the same scene (:mod:`.cycles`)."""

from .cycles import render_blend
from .frames import blender_to_world, world_to_blender
from .scene import export_body_scene, export_scene
from .settings import CyclesSettings, WorldLightSettings
from .world import WorldLight, world_light

__all__ = [
    "export_scene", "export_body_scene", "render_blend", "CyclesSettings", "WorldLightSettings", "world_light",
    "WorldLight", "world_to_blender", "blender_to_world",
]
