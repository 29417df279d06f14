"""Framing: a square crop around the projected body, as a camera that renders exactly that crop.

Kanamori–Endo-style inputs show the person filling a square image. Here the posed mesh
is projected with a *base* camera; the bounding box of its projected vertices (the mask's
box, up to sub-pixel rasterization) is padded, made square and jittered, and a new camera
with the **same view matrix** (so the same rotation: the light frame stays the camera's)
and new intrinsics renders exactly that square at ``res × res``:

    k = res / side,  fx' = k·fx,  fy' = k·fy,  cx' = k·(cx − u0),  cy' = k·(cy − v0)

with ``(u0, v0)`` the crop's top-left corner and ``side`` its size in base-camera pixels.

Modes: ``"full"`` frames the whole body and guarantees a margin of at least
``pad · max(box width, box height)`` on every side (jitter only enlarges the crop and
shifts it within that slack); ``"upper"`` frames the top 55 % of the box (waist up),
``"head"`` the top 25 % (head and shoulders) — measured on the vertices' image-space box,
so a raised arm raises the band; partial crops cut the body, and jitter may shift them
freely by up to ``jitter`` of the side.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from ..checks import InputError, check_finite, check_shape
from ..raster import Camera, perspective_camera

__all__ = ["BASE_INTRINSICS", "CROP_MODES", "CropBox", "base_camera", "camera_intrinsics", "crop_camera", "draw_view",
           "place_in_camera"]

CROP_MODES = ("full", "upper", "head")
#: The generator's base camera (:func:`base_camera`): fx, fy, cx, cy of a 1024² image.
BASE_INTRINSICS = (1000.0, 1000.0, 512.0, 512.0)
_BANDS = {"full": 1.0, "upper": 0.55, "head": 0.25}


@dataclass(frozen=True)
class CropBox:
    """A square crop in base-camera pixels: top-left ``(u0, v0)`` and side ``side``; ``mode``."""

    u0: float
    v0: float
    side: float
    mode: str

    def as_list(self) -> list[float]:
        return [self.u0, self.v0, self.side]


def camera_intrinsics(camera: Camera) -> tuple[float, float, float, float]:
    """``(fx, fy, cx, cy)`` in pixels of the first camera of a perspective :class:`Camera`."""
    P = camera.proj[0].double()
    if float(P[3, 2]) != -1.0 or float(P[3, 3]) != 0.0:
        raise InputError("camera: expected a perspective camera")
    H, W = camera.size
    return (float(P[0, 0]) * W / 2, float(P[1, 1]) * H / 2, (1 - float(P[0, 2])) * W / 2,
            (float(P[1, 2]) + 1) * H / 2)


def crop_camera(
    verts: torch.Tensor,
    base_camera: Camera,
    res: int,
    pad: float = 0.05,
    jitter: float = 0.0,
    rng: np.random.Generator | None = None,
    mode: str = "full",
    near: float = 0.05,
    far: float = 100.0,
) -> tuple[Camera, CropBox]:
    """A camera rendering a square, padded, jittered crop around the projected vertices.

    Args:
        verts: (V, 3) world-frame points to frame (for a clip, all frames' vertices stacked).
        base_camera: a perspective :class:`Camera` (batch 1) in front of which the points lie.
        res: output side in pixels.
        pad: margin around the box, as a fraction of its larger side.
        jitter: random enlargement/shift, as a fraction of the crop side (needs ``rng``).
        rng: random generator for the jitter (None: no jitter).
        mode: one of :data:`CROP_MODES` (module docstring).
        near, far: clipping planes of the new camera.

    Returns:
        (camera, box): a (1-batch) camera with ``base_camera``'s view matrix and size
        ``(res, res)``, and the :class:`CropBox` in base-camera pixels.
    """
    if mode not in CROP_MODES:
        raise InputError(f"crop mode: expected one of {CROP_MODES}, got {mode!r}")
    if int(res) != res or res < 1:
        raise InputError(f"res: expected a positive integer, got {res!r}")
    if not (0 <= pad < 1 and 0 <= jitter < 1):
        raise InputError(f"pad, jitter: expected values in [0, 1), got {pad}, {jitter}")
    check_shape(verts, ["V", 3], name="verts")
    check_finite(verts, "verts")
    if base_camera.batch_size != 1:
        raise InputError(f"base_camera: expected one camera, got {base_camera.batch_size}")
    view = base_camera.world_to_view(verts.to(base_camera.view.dtype))[0]
    if bool((view[:, 2] >= -near).any()):
        raise InputError("crop_camera: some points are behind the camera or nearer than its near plane")
    uv = base_camera.project(verts.to(base_camera.view.dtype))[0].double()
    vmin, vmax = float(uv[:, 1].min()), float(uv[:, 1].max())
    if mode != "full":
        band = uv[:, 1] <= vmin + _BANDS[mode] * (vmax - vmin)
        uv = uv[band]
        vmax = float(uv[:, 1].max())
    umin, umax = float(uv[:, 0].min()), float(uv[:, 0].max())
    w, h = umax - umin, vmax - vmin
    big = max(w, h, 1e-6)
    side = big * (1 + 2 * pad)
    cu, cv = (umin + umax) / 2, (vmin + vmax) / 2
    if rng is not None and jitter > 0:
        a, b, c = rng.uniform(0.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)
        if mode == "full":
            side *= 1 + 2 * jitter * a
            su = max(0.0, (side - w) / 2 - pad * big)  # shifts that keep the margin
            sv = max(0.0, (side - h) / 2 - pad * big)
            cu += b * min(jitter * side, su)
            cv += c * min(jitter * side, sv)
        else:
            side *= 1 + jitter * (2 * a - 1)
            cu += b * jitter * side
            cv += c * jitter * side
    u0, v0 = cu - side / 2, cv - side / 2
    fx, fy, cx, cy = camera_intrinsics(base_camera)
    k = res / side
    intr = (fx * k, fy * k, (cx - u0) * k, (cy - v0) * k)
    cam = perspective_camera(base_camera.view[:1], (res, res), intrinsics=intr, near=near, far=far)
    return cam, CropBox(float(u0), float(v0), float(side), mode)


def _rot_x(a: float) -> torch.Tensor:
    c, s = math.cos(a), math.sin(a)
    return torch.tensor([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]], dtype=torch.float64)


def _rot_y(a: float) -> torch.Tensor:
    c, s = math.cos(a), math.sin(a)
    return torch.tensor([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]], dtype=torch.float64)


def draw_view(rng: np.random.Generator, partial_crop_prob: float) -> dict:
    """The generator's camera placement and crop mode, drawn from ``rng`` (all draws in a fixed order):
    ``{"mode", "distance", "height", "lateral", "pitch_noise"}`` (metres, radians)."""
    partial = bool(rng.uniform() < partial_crop_prob)
    mode = ("upper", "head")[int(rng.integers(2))] if partial else "full"
    return {
        "mode": mode,
        "distance": float(rng.uniform(1.3, 3.0) if partial else rng.uniform(2.5, 6.0)),
        "height": float(rng.uniform(0.6, 1.9)),
        "lateral": float(rng.uniform(-0.4, 0.4)),
        "pitch_noise": float(rng.normal(0.0, math.radians(3))),
    }


def place_in_camera(verts, normals, joints, view: dict, yaw: float):
    """World (T, V, 3) → camera frame: yaw about the pelvis, camera at the view's distance/height, pitched
    toward the crop mode's target height (:func:`draw_view`).

    Returns v_cam, n_cam (T, V, 3) float32, R (3, 3) pitch rotation, pitch, world→camera (4, 4).
    """
    v = verts.double()
    root = joints[0, 0].double()
    pivot = torch.tensor([float(root[0]), 0.0, float(root[2])], dtype=torch.float64)
    Ry = _rot_y(yaw)
    v = (v - pivot) @ Ry.T + pivot
    n = normals.double() @ Ry.T
    y0, y1 = float(v[..., 1].min()), float(v[..., 1].max())
    target = {"full": (y0 + y1) / 2, "upper": y1 - 0.25 * (y1 - y0), "head": y1 - 0.1 * (y1 - y0)}[view["mode"]]
    eye = pivot + torch.tensor([view["lateral"], view["height"], view["distance"]], dtype=torch.float64)
    pitch = math.atan2(view["height"] - target, view["distance"]) + view["pitch_noise"]
    R = _rot_x(pitch)
    w2c = torch.eye(4, dtype=torch.float64)  # world (before yaw) → camera
    w2c[:3, :3] = R @ Ry
    w2c[:3, 3] = R @ (pivot - Ry @ pivot - eye)
    n_cam = n @ R.T
    n_cam = n_cam / n_cam.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    return ((v - eye) @ R.T).float(), n_cam.float(), R, pitch, w2c


def base_camera() -> Camera:
    """The generator's base camera (1024², f = 1000 px, at the origin looking along −z) that
    :func:`crop_camera` crops."""
    return perspective_camera(torch.eye(4)[None], (1024, 1024), intrinsics=BASE_INTRINSICS, near=0.05)
