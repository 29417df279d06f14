"""Cameras: look-at extrinsics, perspective and orthographic projections, batched.

Convention (OpenGL, the only one used anywhere in relightnet):

- **World**: right-handed, +y up (docs/design.md, "Frames").
- **View** (camera) space: the camera sits at the origin and looks along **−z**;
  +x is image right, +y is image up. ``v_view = R v_world + t`` with ``R`` (3, 3)
  the world→camera rotation (rows: the camera's right, up and backward axes in world
  coordinates) and ``t = −R · eye``.
- **Clip** space: ``v_clip = P · (v_view, 1)``, a 4-vector ``(x, y, z, w)``. For a
  perspective camera ``w = −z_view`` (the distance in front of the camera); for an
  orthographic camera ``w = 1``.
- **NDC**: ``(x, y, z) / w``, each in [−1, 1] inside the view volume; ``z_ndc = −1`` on
  the near plane and ``+1`` on the far plane (OpenGL depth range).
- **Pixels**: an image of size ``(H, W)``; pixel ``(row 0, col 0)`` is the **top-left**
  pixel and pixel ``(i, j)`` (row i, column j) covers the square
  ``[j, j+1] × [i, i+1]`` in continuous pixel coordinates ``(u, v)`` (u right, v down),
  so its centre is ``(j + 0.5, i + 0.5)``. ``u = (x_ndc + 1) · W / 2`` and
  ``v = (1 − y_ndc) · H / 2``: NDC y up becomes pixel v down.

Intrinsics ``(fx, fy, cx, cy)`` are in those continuous pixel coordinates: a view-space
point ``(x, y, z)`` with ``z < 0`` lands at ``u = fx · x / (−z) + cx`` and
``v = −fy · y / (−z) + cy``; the image centre is ``(cx, cy) = (W/2, H/2)``. OpenCV
intrinsics put pixel centres on integers: add 0.5 to their ``cx`` and ``cy``.

:func:`default_camera` frames a standing person of about 1.7 m, feet on the ground
(y = 0) at the origin, facing +z: the camera is at ``(0, 0.85, 3)`` looking
horizontally at ``(0, 0.85, 0)`` with a 35° vertical field of view, which shows
2·3·tan(17.5°) ≈ 1.89 m of height at the body's plane.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import torch

from ..checks import InputError, ShapeError, check_shape

__all__ = [
    "Camera",
    "look_at",
    "perspective_projection",
    "fov_projection",
    "orthographic_projection",
    "perspective_camera",
    "orthographic_camera",
    "default_camera",
    "ndc_to_pixel",
    "pixel_to_ndc",
]


def _size(size) -> tuple[int, int]:
    if isinstance(size, int):
        size = (size, size)
    if len(size) != 2 or int(size[0]) < 1 or int(size[1]) < 1:
        raise InputError(f"size: expected (H, W) with positive integers, got {size!r}")
    return int(size[0]), int(size[1])


def _vec(x, name: str, n: int = 3, dtype=torch.float32, device=None) -> torch.Tensor:
    """A (B, n) tensor from a length-n sequence, an (n,) or a (B, n) tensor."""
    t = torch.as_tensor(x, dtype=dtype, device=device)
    if t.dim() == 1:
        t = t[None]
    check_shape(t, ["B", n], name=name)
    return t


def _per_batch(x, name: str, dtype=torch.float32, device=None) -> torch.Tensor:
    """A (B,) tensor from a float or a (B,) tensor."""
    t = torch.as_tensor(x, dtype=dtype, device=device)
    if t.dim() == 0:
        t = t[None]
    check_shape(t, ["B"], name=name)
    return t


def look_at(eye, target, up=(0.0, 1.0, 0.0), dtype=torch.float32, device=None) -> torch.Tensor:
    """World→view matrices of cameras at ``eye`` looking at ``target``.

    Args:
        eye: (3,) or (B, 3) camera positions in world space.
        target: (3,) or (B, 3) points the cameras look at.
        up: (3,) or (B, 3) world direction that appears up in the image.

    Returns:
        (B, 4, 4) view matrices: the camera looks along −z, +y is image up.

    Raises:
        InputError: ``eye == target`` or ``up`` parallel to the viewing direction.
    """
    eye, target, up = (_vec(a, n, dtype=dtype, device=device) for a, n in
                       ((eye, "eye"), (target, "target"), (up, "up")))
    eye, target, up = torch.broadcast_tensors(eye, target, up)
    back = eye - target
    norm = back.norm(dim=-1, keepdim=True)
    if bool((norm < 1e-12).any()):
        raise InputError("look_at: eye and target coincide")
    z = back / norm
    x = torch.linalg.cross(up, z, dim=-1)
    xn = x.norm(dim=-1, keepdim=True)
    if bool((xn < 1e-9).any()):
        raise InputError("look_at: up is parallel to the viewing direction")
    x = x / xn
    y = torch.linalg.cross(z, x, dim=-1)
    R = torch.stack([x, y, z], dim=-2)
    view = torch.zeros(eye.shape[0], 4, 4, dtype=dtype, device=eye.device)
    view[:, :3, :3] = R
    view[:, :3, 3] = -(R @ eye[..., None])[..., 0]
    view[:, 3, 3] = 1.0
    return view


def perspective_projection(fx, fy, cx, cy, size, near: float = 0.1, far: float = 100.0,
                           dtype=torch.float32, device=None) -> torch.Tensor:
    """OpenGL projection matrices from pixel intrinsics (see the module docstring).

    Args:
        fx, fy: focal lengths in pixels, floats or (B,) tensors.
        cx, cy: principal point in continuous pixel coordinates (image centre = W/2, H/2).
        size: (H, W) image size the intrinsics refer to.
        near, far: clipping distances, 0 < near < far.

    Returns:
        (B, 4, 4) projection matrices mapping view space to clip space.
    """
    H, W = _size(size)
    if not 0 < near < far:
        raise InputError(f"near/far: expected 0 < near < far, got near={near}, far={far}")
    fx, fy, cx, cy = torch.broadcast_tensors(
        *(_per_batch(a, n, dtype=dtype, device=device) for a, n in
          ((fx, "fx"), (fy, "fy"), (cx, "cx"), (cy, "cy"))))
    P = torch.zeros(fx.shape[0], 4, 4, dtype=dtype, device=fx.device)
    P[:, 0, 0] = 2 * fx / W
    P[:, 0, 2] = 1 - 2 * cx / W
    P[:, 1, 1] = 2 * fy / H
    P[:, 1, 2] = 2 * cy / H - 1
    P[:, 2, 2] = -(far + near) / (far - near)
    P[:, 2, 3] = -2 * far * near / (far - near)
    P[:, 3, 2] = -1.0
    return P


def fov_projection(fov_deg, size, near: float = 0.1, far: float = 100.0,
                   dtype=torch.float32, device=None) -> torch.Tensor:
    """Centred perspective projections with square pixels from a vertical field of view.

    Args:
        fov_deg: vertical field of view in degrees, float or (B,) tensor.
        size: (H, W).

    Returns:
        (B, 4, 4) projection matrices.
    """
    H, W = _size(size)
    fov = _per_batch(fov_deg, "fov_deg", dtype=torch.float64, device=device)
    if bool(((fov <= 0) | (fov >= 180)).any()):
        raise InputError(f"fov_deg: expected values in (0, 180), got {fov.tolist()}")
    f = (H / 2) / torch.tan(torch.deg2rad(fov) / 2)
    return perspective_projection(f.to(dtype), f.to(dtype), W / 2, H / 2, (H, W), near, far,
                                  dtype=dtype, device=device)


def orthographic_projection(height, size, near: float = 0.1, far: float = 100.0,
                            dtype=torch.float32, device=None) -> torch.Tensor:
    """Centred orthographic projections showing ``height`` world units vertically.

    The width shown is ``height · W / H`` (square pixels); ``w_clip = 1``.

    Args:
        height: visible height in world units, float or (B,) tensor.
        size: (H, W).
        near, far: clipping distances in front of the camera, near < far.

    Returns:
        (B, 4, 4) projection matrices.
    """
    H, W = _size(size)
    if not near < far:
        raise InputError(f"near/far: expected near < far, got near={near}, far={far}")
    h = _per_batch(height, "height", dtype=dtype, device=device)
    P = torch.zeros(h.shape[0], 4, 4, dtype=dtype, device=h.device)
    P[:, 0, 0] = 2 / (h * W / H)
    P[:, 1, 1] = 2 / h
    P[:, 2, 2] = -2 / (far - near)
    P[:, 2, 3] = -(far + near) / (far - near)
    P[:, 3, 3] = 1.0
    return P


def ndc_to_pixel(xy_ndc: torch.Tensor, size) -> torch.Tensor:
    """(..., 2) NDC (x, y) → (..., 2) continuous pixel (u right, v down)."""
    H, W = _size(size)
    u = (xy_ndc[..., 0] + 1) * (W / 2)
    v = (1 - xy_ndc[..., 1]) * (H / 2)
    return torch.stack([u, v], dim=-1)


def pixel_to_ndc(uv: torch.Tensor, size) -> torch.Tensor:
    """(..., 2) continuous pixel (u, v) → (..., 2) NDC (x, y); inverse of :func:`ndc_to_pixel`."""
    H, W = _size(size)
    return torch.stack([uv[..., 0] * (2 / W) - 1, 1 - uv[..., 1] * (2 / H)], dim=-1)


@dataclass(frozen=True)
class Camera:
    """A batch of B cameras rendering (H, W) images (OpenGL convention, module docstring).

    Attributes:
        view: (B, 4, 4) world→view matrices.
        proj: (B, 4, 4) view→clip matrices.
        size: (H, W) image size in pixels.
    """

    view: torch.Tensor
    proj: torch.Tensor
    size: tuple[int, int]

    def __post_init__(self) -> None:
        object.__setattr__(self, "size", _size(self.size))
        dims = check_shape(self.view, ["B", 4, 4], name="view")
        check_shape(self.proj, ["B", 4, 4], name="proj", dims=dims)

    @property
    def batch_size(self) -> int:
        return self.view.shape[0]

    @property
    def R(self) -> torch.Tensor:
        """(B, 3, 3) world→camera rotation: ``n_view = R @ n_world`` for directions."""
        return self.view[:, :3, :3]

    @property
    def t(self) -> torch.Tensor:
        """(B, 3) translation of the world→view transform."""
        return self.view[:, :3, 3]

    @property
    def position(self) -> torch.Tensor:
        """(B, 3) camera centres in world space (``−Rᵀ t``)."""
        return -(self.R.transpose(1, 2) @ self.t[..., None])[..., 0]

    @property
    def full(self) -> torch.Tensor:
        """(B, 4, 4) world→clip matrices ``proj @ view``."""
        return self.proj @ self.view

    def to(self, *args, **kwargs) -> Camera:
        """Move/cast both matrices like ``Tensor.to``."""
        return Camera(self.view.to(*args, **kwargs), self.proj.to(*args, **kwargs), self.size)

    def _verts(self, verts: torch.Tensor) -> torch.Tensor:
        if verts.dim() == 2:
            check_shape(verts, ["V", 3], name="verts")
            return verts[None].expand(self.batch_size, -1, -1)
        check_shape(verts, [self.batch_size, "V", 3], name="verts")
        return verts

    def world_to_view(self, verts: torch.Tensor) -> torch.Tensor:
        """(V, 3) or (B, V, 3) world points → (B, V, 3) view-space points."""
        v = self._verts(verts)
        return v @ self.R.to(v).transpose(1, 2) + self.t.to(v)[:, None]

    def transform(self, verts: torch.Tensor) -> torch.Tensor:
        """(V, 3) or (B, V, 3) world points → (B, V, 4) clip-space points (input of ``rasterize``)."""
        v = self._verts(verts)
        M = self.full.to(v)
        return v @ M[:, :, :3].transpose(1, 2) + M[:, None, :, 3]

    def project(self, verts: torch.Tensor) -> torch.Tensor:
        """(V, 3) or (B, V, 3) world points → (B, V, 2) continuous pixel coordinates (u, v).

        Points behind a perspective camera (``w <= 0``) give meaningless values.
        """
        c = self.transform(verts)
        return ndc_to_pixel(c[..., :2] / c[..., 3:], self.size)

    def depth_to_view(self, depth: torch.Tensor) -> torch.Tensor:
        """NDC depth (``Fragments.depth``) → distance in front of the camera (−z_view).

        Args:
            depth: (B, ...) NDC z; +inf (background) stays +inf.

        Returns:
            (B, ...) positive view-space depth.
        """
        if depth.shape[0] != self.batch_size:
            raise ShapeError(f"depth: expected batch {self.batch_size}, got shape {tuple(depth.shape)}")
        P = self.proj.to(depth).reshape(self.batch_size, *([1] * (depth.dim() - 1)), 4, 4)
        a, b, c, d = P[..., 2, 2], P[..., 2, 3], P[..., 3, 2], P[..., 3, 3]
        # z_ndc = (a z + b) / (c z + d)  =>  z = (b - z_ndc d) / (z_ndc c - a)
        z = (b - depth * d) / (depth * c - a)
        return torch.where(torch.isinf(depth), depth, -z)


def perspective_camera(view: torch.Tensor, size, fov_deg=None, intrinsics: Sequence | None = None,
                       near: float = 0.1, far: float = 100.0) -> Camera:
    """A perspective :class:`Camera` from view matrices and either a vertical FOV or intrinsics.

    Args:
        view: (B, 4, 4) world→view matrices (e.g. from :func:`look_at`).
        size: (H, W).
        fov_deg: vertical field of view in degrees (float or (B,)).
        intrinsics: ``(fx, fy, cx, cy)`` in pixels (module docstring); exclusive with ``fov_deg``.
    """
    if (fov_deg is None) == (intrinsics is None):
        raise InputError("perspective_camera: give exactly one of fov_deg and intrinsics")
    if fov_deg is not None:
        P = fov_projection(fov_deg, size, near, far, dtype=view.dtype, device=view.device)
    else:
        P = perspective_projection(*intrinsics, size, near, far, dtype=view.dtype, device=view.device)
    if P.shape[0] != view.shape[0]:
        P = P.expand(view.shape[0], 4, 4) if P.shape[0] == 1 else P
        view = view.expand(P.shape[0], 4, 4) if view.shape[0] == 1 else view
    return Camera(view, P, size)


def orthographic_camera(view: torch.Tensor, size, height, near: float = 0.1, far: float = 100.0) -> Camera:
    """An orthographic :class:`Camera` showing ``height`` world units vertically."""
    P = orthographic_projection(height, size, near, far, dtype=view.dtype, device=view.device)
    if P.shape[0] != view.shape[0]:
        P = P.expand(view.shape[0], 4, 4) if P.shape[0] == 1 else P
        view = view.expand(P.shape[0], 4, 4) if view.shape[0] == 1 else view
    return Camera(view, P, size)


def default_camera(size=(512, 512), fov_deg: float = 35.0, distance: float = 3.0,
                   target=(0.0, 0.85, 0.0), batch_size: int = 1, near: float = 0.1,
                   far: float = 100.0, device=None) -> Camera:
    """The default full-body camera: at ``target + (0, 0, distance)`` looking along −z.

    With the defaults it frames a ~1.7 m person standing at the origin, feet at y = 0,
    facing +z (module docstring).

    Args:
        size: (H, W) or an int for square images.
        batch_size: B identical cameras.

    Returns:
        A :class:`Camera` with (B, 4, 4) float32 matrices.
    """
    if distance <= 0 or not math.isfinite(distance):
        raise InputError(f"distance: expected a positive number, got {distance}")
    tgt = torch.as_tensor(target, dtype=torch.float32, device=device)
    eye = tgt + torch.tensor([0.0, 0.0, float(distance)], device=device)
    view = look_at(eye, tgt, device=device).expand(batch_size, 4, 4).contiguous()
    return perspective_camera(view, size, fov_deg=fov_deg, near=near, far=far)
