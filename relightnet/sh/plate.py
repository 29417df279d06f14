"""The light of a background plate: an environment map made from the photo itself, projected to SH.

A plate (the scene a person is put into, seen by the camera) shows only the part of the
light in the camera's frustum, in front of the camera. :func:`plate_envmap` places that part
on a lat-long map and fills the rest by one rule:

1. **Frustum.** A direction d (world frame, camera at the origin looking along −z) inside
   the pinhole frustum of horizontal field of view ``hfov_deg`` takes the plate's pixel
   (the plate is first area-downsampled to ``work`` pixels across, a defocused view: the
   light's band limit needs no more).
2. **Sides, sky and ground** (front half-space, outside the frustum): the pinhole
   projection is continued to the border (the nearest edge pixel along the same image-plane
   ray: clamped coordinates), then blended toward the mean of the plate's top band (sky,
   the top ``band`` of the rows) above the frustum and toward its bottom band (ground) below
   it, with a weight growing linearly from 0 at the edge of the frustum to 1 at the zenith
   or nadir.
3. **Behind the camera** (d_z > 0): the front half mirrored through the image plane,
   ``(x, y, z) → (x, y, −z)``. The camera-side light is what a person facing the camera
   receives and what the plate cannot show; the mirror keeps the plate's left/right and
   sky/ground structure and its colour, and adds no front/back asymmetry it cannot know.

Units: the plate is decoded to linear light (inverse sRGB; no normalisation, the exposure is
kept) and divided by π, the generator's convention (a white Lambertian person shows irradiance
E = π × radiance, docs/design.md "Transport and shading"): a white person lit by a uniform
plate of value p shows p.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F

from ..checks import InputError, check_finite, check_shape, sh_order_from_count
from .directions import latlong_directions
from .projection import project_envmap

__all__ = ["plate_envmap", "plate_light", "load_plate_light", "combine_person_plate", "DEFAULT_HFOV"]

#: The horizontal field of view assumed for a plate when none is given (degrees): a normal lens.
DEFAULT_HFOV = 60.0


def _downsample(img: torch.Tensor, work: int) -> torch.Tensor:
    """(H, W, 3) → (h, work, 3) by area averaging (h keeps the aspect ratio)."""
    h, w = img.shape[:2]
    if w <= work:
        return img
    hh = max(1, round(h * work / w))
    return F.adaptive_avg_pool2d(img.permute(2, 0, 1)[None], (hh, work))[0].permute(1, 2, 0)


def plate_envmap(plate: torch.Tensor, hfov_deg: float = DEFAULT_HFOV, h: int = 64, work: int = 64,
                 band: float = 0.15, intrinsics=None) -> torch.Tensor:
    """The lat-long environment map of a plate (module docstring).

    Args:
        plate: (H, W, 3) linear RGB plate (e.g. :func:`relightnet.io.read_image` with ``linear=True``).
        hfov_deg: the camera's horizontal field of view, degrees (0, 170).
        h: map height (width 2h).
        work: width the plate is averaged down to before sampling.
        band: fraction of rows whose mean is the sky (top) and the ground (bottom).
        intrinsics: ``(fx, fy, cx, cy)`` in the plate's pixels when known (then ``hfov_deg`` is
            not used); default: a centred pinhole of ``hfov_deg``.

    Returns:
        (H', 2H', 3) float32 radiance, world frame (H' = ``h``), in the plate's exposure / π.
    """
    check_shape(plate, ["H", "W", 3], name="plate")
    if not plate.is_floating_point():
        raise InputError(f"plate: expected a floating-point linear image, got {plate.dtype}")
    check_finite(plate, "plate")
    if not 0 < hfov_deg < 170:
        raise InputError(f"plate field of view: expected 0 to 170 degrees, got {hfov_deg:g}")
    img = _downsample(plate.double().clamp_min(0), work)
    ph, pw = img.shape[:2]
    if intrinsics is None:
        fx = fy = 0.5 * pw / math.tan(math.radians(hfov_deg) / 2)
        cx, cy = 0.5 * pw, 0.5 * ph
    else:
        s = pw / plate.shape[1]
        fx, fy, cx, cy = (float(v) * s for v in intrinsics)
    dirs, _ = latlong_directions(h, 2 * h, dtype=torch.float64)
    x, y, z = dirs.unbind(-1)
    zf = -z.abs()  # behind the camera: mirrored to the front
    depth = (-zf).clamp_min(1e-6)
    # Image-plane offsets from the principal point, continued to the border: beyond it the ray
    # from the principal point is shrunk onto the frame (the nearest edge pixel along it).
    du, dv = fx * x / depth, -fy * y / depth
    room_u = torch.where(du > 0, pw - 0.5 - cx, cx - 0.5).clamp_min(0)
    room_v = torch.where(dv > 0, ph - 0.5 - cy, cy - 0.5).clamp_min(0)
    scale = torch.minimum(room_u / du.abs().clamp_min(1e-12), room_v / dv.abs().clamp_min(1e-12)).clamp(max=1.0)
    grid = torch.stack([(cx + du * scale) / (0.5 * pw) - 1, (cy + dv * scale) / (0.5 * ph) - 1], -1)
    seen = F.grid_sample(img.permute(2, 0, 1)[None], grid[None], mode="bilinear", padding_mode="border",
                         align_corners=False)[0].permute(1, 2, 0)
    nb = max(1, round(band * ph))
    sky, ground = img[:nb].mean((0, 1)), img[-nb:].mean((0, 1))
    # Elevation of the frustum's top/bottom edge along this azimuth, and the blend weight beyond it.
    elev = torch.asin(y.clamp(-1, 1))
    cos_az = torch.cos(torch.atan2(x, -zf))  # the azimuth is within ±90°
    top, bottom = torch.atan(cy / fy * cos_az), torch.atan((ph - cy) / fy * cos_az)
    w_up = ((elev - top) / (math.pi / 2 - top)).clamp(0, 1)[..., None]
    w_down = ((-elev - bottom) / (math.pi / 2 - bottom)).clamp(0, 1)[..., None]
    env = seen * (1 - w_up - w_down) + w_up * sky + w_down * ground
    return (env / math.pi).float()


def plate_light(plate: torch.Tensor, lmax: int = 2, hfov_deg: float = DEFAULT_HFOV, intrinsics=None) -> torch.Tensor:
    """The SH light of a plate: :func:`plate_envmap` projected (:func:`relightnet.sh.project_envmap`).

    Args:
        plate: (H, W, 3) linear RGB.
        lmax: SH order.
        hfov_deg: horizontal field of view of the plate's camera, degrees.
        intrinsics: ``(fx, fy, cx, cy)`` in the plate's pixels, when known (overrides ``hfov_deg``).

    Returns:
        (K, 3) float32 linear RGB radiance, light frame (camera-relative).
    """
    env = plate_envmap(plate, hfov_deg, h=max(64, 16 * (lmax + 1)), intrinsics=intrinsics)
    return project_envmap(env.double(), lmax).float()


def load_plate_light(path, lmax: int = 2, hfov_deg: float = DEFAULT_HFOV, frame: int = 0) -> torch.Tensor:
    """The SH light of a plate file: an image (sRGB, 8 or 16 bit) or a video's frame ``frame``.

    Decoding is bounded by the pixel limit (:mod:`relightnet.io.limits`); the pixels are
    linearised by the inverse sRGB curve, exposure kept.

    Returns:
        (K, 3) float32, as :func:`plate_light`.

    Raises:
        InputError: a missing or unreadable file, or a video without that frame (named).
    """
    from pathlib import Path

    from ..color import srgb_to_linear
    from ..io import read_image

    p = Path(path)
    if not p.is_file():
        raise InputError(f"plate {p}: no such file")
    if p.suffix.lower() in (".mp4", ".mkv", ".mov", ".avi", ".webm"):
        from ..io import read_video

        for i, img in enumerate(read_video(p)):
            if i == frame:
                rgb = srgb_to_linear(torch.as_tensor(img).float() / 255)
                break
        else:
            raise InputError(f"plate {p}: the video has no frame {frame}")
    else:
        rgb = read_image(p, linear=True)
    return plate_light(rgb, lmax, hfov_deg)


def combine_person_plate(person: torch.Tensor, plate: torch.Tensor, width: float = 0.5) -> torch.Tensor:
    """One light from the person-based estimate and the plate's: each where it sees best.

    The person's estimate is trusted on the camera side (the person faces the camera; light
    from behind them barely reaches the visible pixels), the plate's on the far side (what
    the plate shows). Radiance is blended by the weight ``w(ω) = clamp(½ + x_light / (2·width))``
    on the person's light, on a Fibonacci sphere, and projected back; both lights are used at
    their own scale (both are in the photo's exposure).

    Args:
        person: (K, 3) or (T, K, 3) light estimated from the person.
        plate: (K, 3) light of the plate.
        width: half-width of the blend around the image plane, in x_light (0, 1].

    Returns:
        Like ``person``: float32.
    """
    from .basis import sh_basis
    from .directions import fibonacci_sphere

    check_shape(plate, ["K", 3], name="plate")
    check_shape(person, ["...", plate.shape[0], 3], name="person")

    lmax = sh_order_from_count(plate.shape[0])
    d, wq = fibonacci_sphere(4096, dtype=torch.float64)
    Y = sh_basis(d, lmax, check=False)  # (D, K)
    w = (0.5 + d[:, 0] / (2 * width)).clamp(0, 1)
    # SH → radiance → blend → SH is linear: L = Yᵀ diag(wq w) Y L_person + Yᵀ diag(wq (1 − w)) Y L_plate.
    Mp = (Y * (wq * w)[:, None]).T @ Y
    Mb = (Y * (wq * (1 - w))[:, None]).T @ Y
    return (Mp @ person.double() + Mb @ plate.double()).float()
