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

With a person in front of the plate, :func:`combine_person_plate` keeps the person's estimate
and takes the plate only where its frame shows the light (:func:`plate_seen`).

Units: the plate is decoded to linear light (inverse sRGB; no normalisation, the exposure is
kept) and divided by π, the generator's convention (a white Lambertian person shows irradiance
E = π × radiance, docs/design.md "Transport and shading"): a white person lit by a uniform
plate of value p shows p.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import torch
import torch.nn.functional as F

from ..checks import InputError, check_finite, check_shape, sh_order_from_count
from ..sh.directions import latlong_directions
from ..sh.projection import project_envmap

__all__ = ["plate_envmap", "plate_light", "load_plate_light", "load_plate", "combine_person_plate", "plate_view",
           "plate_seen", "Plate", "PlateView", "DEFAULT_HFOV", "SEEN_FADE_DEG"]

#: The horizontal field of view assumed for a plate when none is given (degrees): a normal lens.
DEFAULT_HFOV = 60.0
#: How far outside the plate's frame (degrees) its weight in :func:`combine_person_plate` falls
#: to 0: a soft edge, so the blend has no step for the SH projection to ring on.
SEEN_FADE_DEG = 10.0


class PlateView(NamedTuple):
    """The pinhole a plate was seen through: ``fx, fy, cx, cy`` and its ``width, height``, in pixels."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int


class Plate(NamedTuple):
    """A plate's light (K, 3) (:func:`plate_light`) and the view it was seen through."""

    light: torch.Tensor
    view: PlateView


def plate_view(height: int, width: int, hfov_deg: float = DEFAULT_HFOV, intrinsics=None) -> PlateView:
    """The view of a ``height`` × ``width`` plate: its ``intrinsics`` when known, else a centred
    pinhole of horizontal field of view ``hfov_deg`` (square pixels)."""
    if intrinsics is not None:
        fx, fy, cx, cy = (float(v) for v in intrinsics)
        return PlateView(fx, fy, cx, cy, int(width), int(height))
    if not 0 < hfov_deg < 170:
        raise InputError(f"plate field of view: expected 0 to 170 degrees, got {hfov_deg:g}")
    f = 0.5 * width / math.tan(math.radians(hfov_deg) / 2)
    return PlateView(f, f, 0.5 * width, 0.5 * height, int(width), int(height))


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
    view = plate_view(plate.shape[0], plate.shape[1], hfov_deg, intrinsics)
    img = _downsample(plate.double().clamp_min(0), work)
    ph, pw = img.shape[:2]
    s = pw / plate.shape[1]
    fx, fy, cx, cy = view.fx * s, view.fy * s, view.cx * s, view.cy * s
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


def load_plate(path, lmax: int = 2, hfov_deg: float = DEFAULT_HFOV, frame: int = 0) -> Plate:
    """A plate file's light and view: an image (sRGB, 8 or 16 bit) or a video's frame ``frame``.

    Decoding is bounded by the pixel limit (:mod:`relightnet.io.limits`); the pixels are
    linearised by the inverse sRGB curve, exposure kept.

    Returns:
        :class:`Plate`: the (K, 3) float32 light of :func:`plate_light` and the centred pinhole
        of ``hfov_deg`` at the plate's size.

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
    return Plate(plate_light(rgb, lmax, hfov_deg), plate_view(rgb.shape[0], rgb.shape[1], hfov_deg))


def load_plate_light(path, lmax: int = 2, hfov_deg: float = DEFAULT_HFOV, frame: int = 0) -> torch.Tensor:
    """The (K, 3) float32 SH light of a plate file: :func:`load_plate`'s ``light``."""
    return load_plate(path, lmax, hfov_deg, frame).light


def plate_seen(dirs: torch.Tensor, view: PlateView, fade_deg: float = SEEN_FADE_DEG) -> torch.Tensor:
    """How much of each direction the plate shows: 1 inside its frame, falling linearly to 0 at
    ``fade_deg`` outside it (per image axis), 0 behind the camera.

    Args:
        dirs: (N, 3) unit directions in the light frame.
        view: the plate's :class:`PlateView`.
        fade_deg: width of the soft edge, degrees (> 0).

    Returns:
        (N,) weights in [0, 1], dtype of ``dirs``.
    """
    from ..sh.frames import light_to_world

    check_shape(dirs, ["N", 3], name="dirs")
    if not fade_deg > 0:
        raise InputError(f"plate_seen: fade_deg must be > 0 degrees, got {fade_deg}")
    x, y, z = light_to_world(dirs).unbind(-1)
    depth = (-z).clamp_min(1e-12)
    ax, ay = torch.atan2(x, depth), torch.atan2(y, depth)  # angles right of and above the axis
    left, right = -math.atan(view.cx / view.fx), math.atan((view.width - view.cx) / view.fx)
    top, bottom = math.atan(view.cy / view.fy), -math.atan((view.height - view.cy) / view.fy)
    fade = math.radians(fade_deg)
    out_x = torch.maximum(left - ax, ax - right).clamp_min(0)
    out_y = torch.maximum(ay - top, bottom - ay).clamp_min(0)
    w = (1 - out_x / fade).clamp(0, 1) * (1 - out_y / fade).clamp(0, 1)
    return w * (z < 0).to(w.dtype)


def combine_person_plate(person: torch.Tensor, plate: torch.Tensor, view: PlateView,
                         fade_deg: float = SEEN_FADE_DEG) -> torch.Tensor:
    """One light from the person-based estimate and the plate's: the plate where it was seen.

    Inside the plate's frame (:func:`plate_seen`) the plate shows the light itself, the light
    behind the person that their visible pixels barely respond to; everywhere else the plate's
    light is only its fill rule's guess (:func:`plate_envmap`) and the person's estimate is
    kept. Radiance is blended by that weight on a Fibonacci sphere and projected back (a linear
    map of the two lights); both lights are used at their own scale (both are in the photo's
    exposure).

    Args:
        person: (K, 3) or (T, K, 3) light estimated from the person.
        plate: (K, 3) light of the plate.
        view: the view the plate was seen through (:class:`Plate`'s ``view``).
        fade_deg: the soft edge of the plate's frame, degrees.

    Returns:
        Like ``person``: float32.
    """
    from ..sh.basis import sh_basis
    from ..sh.directions import fibonacci_sphere

    check_shape(plate, ["K", 3], name="plate")
    check_shape(person, ["...", plate.shape[0], 3], name="person")

    lmax = sh_order_from_count(plate.shape[0])
    d, wq = fibonacci_sphere(4096, dtype=torch.float64)
    Y = sh_basis(d, lmax, check=False)  # (D, K)
    w = plate_seen(d, view, fade_deg)  # the plate's weight
    # SH → radiance → blend → SH is linear: L = Yᵀ diag(wq (1 − w)) Y L_person + Yᵀ diag(wq w) Y L_plate.
    Mp = (Y * (wq * (1 - w))[:, None]).T @ Y
    Mb = (Y * (wq * w)[:, None]).T @ Y
    return (Mp @ person.double() + Mb @ plate.double()).float()
