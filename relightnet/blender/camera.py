"""relightnet :class:`~relightnet.raster.Camera` → Blender camera settings (no bpy needed).

Blender's camera with ``sensor_fit = "HORIZONTAL"`` has its view plane W pixels wide:
``lens / sensor_width = fx / W`` (focal length in pixels), and ``shift_x``, ``shift_y``
move the view plane in units of that width. With relightnet's intrinsics
(:mod:`relightnet.raster.camera`: principal point ``(cx, cy)`` in continuous pixels, v down)
the principal point of a Blender camera is ``cx = W/2 − shift_x·W``, ``cy = H/2 + shift_y·W``.
All of them are read off the OpenGL projection matrix P:
``fx = P00·W/2``, ``fy = P11·H/2``, ``shift_x = P02/2``, ``shift_y = P12·H/(2W)``, clip
distances from P22, P23. Orthographic cameras map to ``type="ORTHO"`` with
``ortho_scale`` = the visible width. Pixels must be square (fx = fy). Extrinsics go
through :func:`relightnet.blender.frames.transform_to_blender`. The tests project points
with Blender's own ``world_to_camera_view`` and compare with :meth:`Camera.project`.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from ..checks import InputError, ShapeError
from ..raster import Camera
from .frames import transform_to_blender

__all__ = ["SENSOR_WIDTH_MM", "BlenderCamera", "blender_camera"]

#: Sensor width written to Blender (its default full-frame 36 mm); only lens/sensor matters.
SENSOR_WIDTH_MM = 36.0


@dataclass(frozen=True)
class BlenderCamera:
    """The settings of one Blender camera object equal to a relightnet camera.

    Attributes:
        matrix_world: 4×4 nested tuple, camera → Blender world.
        type: ``"PERSP"`` or ``"ORTHO"``.
        lens: focal length in mm (perspective) for a ``sensor_width`` of :data:`SENSOR_WIDTH_MM`.
        ortho_scale: visible width in metres (orthographic).
        shift_x, shift_y: view-plane shift in units of the image width.
        clip_start, clip_end: near and far distances.
        resolution: (W, H) pixels.
    """

    matrix_world: tuple
    type: str
    lens: float
    ortho_scale: float
    shift_x: float
    shift_y: float
    clip_start: float
    clip_end: float
    resolution: tuple[int, int]


def blender_camera(camera: Camera) -> BlenderCamera:
    """Blender settings of one relightnet camera (module docstring).

    Args:
        camera: a batch of exactly one camera.

    Raises:
        ShapeError: more than one camera. InputError: non-square pixels or a skewed projection.
    """
    if camera.batch_size != 1:
        raise ShapeError(f"camera: expected one camera, got a batch of {camera.batch_size}")
    H, W = camera.size
    P = camera.proj[0].to(torch.float64)
    view = camera.view[0].to(torch.float64)
    ortho = bool(P[3, 3] == 1 and P[3, 2] == 0)
    skew = [P[0, 1], P[1, 0]] + ([P[0, 2], P[1, 2]] if ortho else [P[0, 3], P[1, 3]])
    if any(abs(float(s)) > 1e-9 for s in skew):
        raise InputError("camera: skewed or off-axis projections have no Blender equivalent")
    fx, fy = float(P[0, 0]) * W / 2, float(P[1, 1]) * H / 2
    if abs(fx - fy) > 1e-5 * max(abs(fx), abs(fy)):
        raise InputError(f"camera: Blender needs square pixels, got fx={fx:.6g} and fy={fy:.6g} (pixels)")
    if ortho:
        near, far = float((P[2, 3] + 1) / P[2, 2]), float((P[2, 3] - 1) / P[2, 2])
        sx, sy = -float(P[0, 3]) / 2, -float(P[1, 3]) * H / (2 * W)
        lens, scale = 50.0, 2.0 / float(P[0, 0])
    else:
        near, far = float(P[2, 3] / (P[2, 2] - 1)), float(P[2, 3] / (P[2, 2] + 1))
        sx, sy = float(P[0, 2]) / 2, float(P[1, 2]) * H / (2 * W)
        lens, scale = fx / W * SENSOR_WIDTH_MM, 1.0
    mw = transform_to_blender(torch.linalg.inv(view))
    return BlenderCamera(
        matrix_world=tuple(tuple(float(x) for x in row) for row in mw.tolist()),
        type="ORTHO" if ortho else "PERSP", lens=lens, ortho_scale=scale, shift_x=sx, shift_y=sy,
        clip_start=near, clip_end=far, resolution=(W, H),
    )
