"""3D-path rendering: shading and compositing primitives, the frame renderer, whole render jobs."""

from .frame import RenderOutput, TexturedAlbedo, light_in_world, render_mesh
from .jobs import BodyFrame, LoadedMesh, fit_camera, load_mesh, render_body_frames, render_mesh_file
from .shading import Shade, composite, composite_covered, shade, shading

__all__ = [
    "RenderOutput", "TexturedAlbedo", "light_in_world", "render_mesh",
    "BodyFrame", "LoadedMesh", "fit_camera", "load_mesh", "render_body_frames", "render_mesh_file",
    "Shade", "composite", "composite_covered", "shade", "shading",
]
