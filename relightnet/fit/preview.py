"""What a person looks at to judge a fit: the fitted mesh over the frames, and its silhouette.

:func:`fit_meshes` poses the whole mesh for a :class:`FitResult`; :func:`fit_silhouettes`
rasterizes it in the input's camera; :func:`overlay_frames` draws it, shaded by how much
each surface faces the camera, half-transparent over the frames.
"""

from __future__ import annotations

import torch

from ..checks import check_shape
from ..raster import Camera, rasterize
from ..raster.camera import perspective_projection
from ..raster.interpolate import interpolate_pixels
from .body_model import FitBody
from .solve import FitResult

__all__ = ["CHUNK_PIXELS", "chunk_frames", "fit_camera", "fit_meshes", "fit_silhouettes", "overlay_frames"]

#: Pixels of the frames rasterized or drawn together (frames × H × W): 8 frames of 512², one frame from 2 MP
#: up. A 12.5 MP frame alone takes ~1 GB here (the frame and its overlay as float, the rasterizer's buffers).
CHUNK_PIXELS = 1 << 21


def chunk_frames(size: tuple[int, int], most: int = 8) -> int:
    """How many frames of (H, W) to rasterize or draw together: at most ``most``, within :data:`CHUNK_PIXELS`
    (at least 1)."""
    return max(1, min(int(most), CHUNK_PIXELS // max(int(size[0]) * int(size[1]), 1)))


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


def fit_silhouettes(result: FitResult, fb: FitBody, chunk: int | None = None, start: int = 0,
                    stop: int | None = None) -> torch.Tensor:
    """(stop − start, H, W) float32 masks of the fitted body in the input's camera, frames [start, stop)
    (default: all T), rasterized ``chunk`` frames at a time (default: :func:`chunk_frames`)."""
    stop = result.pose.shape[0] if stop is None else stop
    chunk = chunk_frames(result.size) if chunk is None else chunk
    return torch.cat([_frags(result, fb, a, min(a + chunk, stop))[1].mask.float() for a in range(start, stop, chunk)])


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
    # Only the covered pixels change (elsewhere frames × (1 − 0) + colour × 0 is the frame): they are blended
    # one by one (N of them), not as whole (B, 3, H, W) images (at 12.5 MP each is 150 MB).
    n = interpolate_pixels(out.normals, fr, out.faces)  # (N, 3), view space
    shade = 0.25 + 0.75 * n[:, 2].clamp(0, 1)
    colour = torch.tensor([0.55, 0.75, 1.0])[:, None] * shade  # (3, N)
    a = torch.tensor(opacity, dtype=frames.dtype)
    img = torch.clamp(frames, 0, 1, out=torch.empty(frames.shape, dtype=frames.dtype))  # a contiguous copy
    HW = result.size[0] * result.size[1]
    at = (fr.pix // HW) * (3 * HW) + fr.pix % HW  # channel 0 of each covered pixel in img's flat storage
    flat = img.view(-1)
    for c in range(3):
        idx = at + c * HW
        flat[idx] = (flat[idx] * (1 - a) + colour[c] * a).clamp(0, 1)
    return img
