"""3D-path rendering: shading and compositing primitives, the frame renderer, whole render jobs.

The public names are the primitives (:func:`shade`, :class:`Shade`, :func:`composite`), the frame
renderer (:func:`render_mesh` → :class:`RenderOutput`, with a :class:`TexturedAlbedo`; the light frame
of a camera: :func:`light_in_world`) and the render jobs (:func:`render_body_frames` → :class:`BodyFrame`,
:func:`render_mesh_file`); the mesh loading and the covered composite stay in their modules.

The names load on first use (:func:`relightnet.lazy.lazy_package`): the shading primitives do not
pull in the frame renderer's ray tracer."""

from __future__ import annotations

from ..lazy import lazy_package

#: public name → the module of this package that defines it
_EXPORTS = {
    "RenderOutput": "frame", "TexturedAlbedo": "frame", "light_in_world": "frame", "render_mesh": "frame",
    "render_body_frames": "jobs", "render_mesh_file": "jobs", "BodyFrame": "jobs", "shade": "shading",
    "Shade": "shading", "composite": "shading",
}

__all__ = lazy_package(__name__, _EXPORTS)
