"""What a person looks at to judge a fit: the fitted mesh over the frames, and its silhouette.

:func:`fit_meshes` poses the whole mesh for a :class:`FitResult`; :func:`fit_silhouettes`
rasterizes it in the input's camera; :func:`overlay_frames` draws it, shaded by how much
each surface faces the camera, half-transparent over the frames.
"""

from __future__ import annotations

import torch

from ..checks import check_shape
from ..raster import Camera, interpolate, perspective_projection, rasterize
from .body_model import FitBody
from .solve import FitResult

__all__ = ["fit_camera", "fit_meshes", "fit_silhouettes", "overlay_frames"]


def fit_camera(result: FitResult, batch: int = 1) -> Camera:
    """The input's camera: identity view (the fit is in view space) and the fit's intrinsics."""
    P = perspective_projection(*result.intrinsics, result.size)
    return Camera(torch.eye(4)[None].expand(batch, 4, 4), P.expand(batch, 4, 4), result.size)


def fit_meshes(result: FitResult, fb: FitBody, start: int = 0, stop: int | None = None):
    """The posed :class:`relightnet.body.BodyOutput` of frames [start, stop) (view space)."""
    sl = slice(start, stop)
    with torch.no_grad():
        return fb(result.pose[sl], result.trans[sl], fb.body.phenotype_tensor(result.phenotype[None]))[2]


def _frags(result: FitResult, fb: FitBody, start: int, stop: int):
    out = fit_meshes(result, fb, start, stop)
    cam = fit_camera(result, out.verts.shape[0])
    return out, rasterize(cam.transform(out.verts), out.faces, result.size)


def fit_silhouettes(result: FitResult, fb: FitBody, chunk: int = 8) -> torch.Tensor:
    """(T, H, W) float32 masks of the fitted body in the input's camera."""
    T = result.pose.shape[0]
    return torch.cat([_frags(result, fb, a, min(a + chunk, T))[1].mask.float() for a in range(0, T, chunk)])


def overlay_frames(frames: torch.Tensor, result: FitResult, fb: FitBody, start: int = 0,
                   opacity: float = 0.6) -> torch.Tensor:
    """Frames with the fitted mesh drawn over them.

    Args:
        frames: (B, 3, H, W) sRGB in [0, 1], frames [start, start + B) of the fit.

    Returns:
        (B, 3, H, W) sRGB in [0, 1].
    """
    d = check_shape(frames, ["B", 3, result.size[0], result.size[1]], name="frames")
    out, fr = _frags(result, fb, start, start + d["B"])
    n = interpolate(out.normals, fr, out.faces)  # (B, H, W, 3), view space
    shade = (0.25 + 0.75 * n[..., 2].clamp(0, 1))[:, None]
    colour = torch.tensor([0.55, 0.75, 1.0])[None, :, None, None] * shade
    a = opacity * fr.mask.float()[:, None]
    return (frames * (1 - a) + colour * a).clamp(0, 1)
