"""The Blender world image of a relightnet light: an SH light or an environment map.

- **SH light** (K, 3): the lat-long image reconstructed from the coefficients,
  ``L(ω) = Σ_k L_k Y_k(ω)``, evaluated exactly at the centre of every pixel of Blender's
  equirectangular layout (no resampling). Order-2 lights ring: most presets reach negative
  radiance in some directions (5–28 % of their power). Cycles clamps a negative background
  to 0 (measured: a world of −1 renders as 0), so the negative part is handled explicitly:
  ``negative="clamp"`` (default) sets it to 0, which *adds* light compared with relightnet's
  render of the same coefficients; ``negative="lift"`` adds the smallest per-channel
  constant making the reconstruction non-negative (still band-limited: only L_0 changes),
  and :attr:`WorldLight.sh` holds the lifted coefficients so relightnet can render the very
  same light.
- **Environment map** (a preset name or an ``.exr``/``.hdr`` file): the full map, rolled
  into Blender's layout (:func:`relightnet.blender.frames.latlong_to_equirect`) or, when the
  light is camera-relative and the camera is rotated, resampled bilinearly.

Lights in relightnet's avatar pipeline are relative to the camera (``light_frame="camera"``,
docs/design.md, "Frames"); Blender's world is fixed, so they are turned into the world frame first, like
:func:`relightnet.render.light_in_world` does for SH: the world radiance in direction d is
the camera-frame radiance in direction ``R d`` (R = world→camera rotation).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import torch

from ..checks import InputError, ShapeError, check_finite, check_sh_count, check_shape
from ..light import load_light
from ..raster import Camera
from ..sh import directions_to_latlong, project_envmap, radiance, world_to_light
from .frames import equirect_directions, latlong_to_equirect

__all__ = ["WorldLight", "world_light", "sh_world_image", "envmap_world_image", "lift_sh"]

_ENV_SUFFIXES = (".exr", ".hdr")
_NEGATIVE = ("clamp", "lift")


@dataclass(frozen=True, eq=False)
class WorldLight:
    """A light ready for Blender's world.

    Attributes:
        image: (H, W, 3) float32 linear radiance ≥ 0 in Blender's equirectangular layout
            (row 0 = top = up), fixed to the world.
        sh: (K, 3) SH light in the *world's* light frame: the coefficients of the image for an
            SH world (lifted when ``negative="lift"``), the projection of the map for an
            environment map. Render it with ``light_frame="world"``.
        kind: ``"sh"`` (band-limited reconstruction) or ``"envmap"`` (the full map).
        source: what the light was made from (a name, a path or ``"tensor"``).
        negative: fraction of the reconstruction's power that was negative (0 for maps).
    """

    image: torch.Tensor
    sh: torch.Tensor
    kind: str
    source: str
    negative: float = 0.0


def _rotation(camera: Camera | None, light_frame: str) -> torch.Tensor | None:
    """World→camera rotation (3, 3) for camera-relative lights, None when it is the identity."""
    if light_frame not in ("camera", "world"):
        raise InputError(f"light_frame: expected 'camera' or 'world', got {light_frame!r}")
    if light_frame == "world" or camera is None:
        return None
    if camera.batch_size != 1:
        raise ShapeError(f"camera: expected one camera, got a batch of {camera.batch_size}")
    R = camera.R[0].to(torch.float64)
    return None if torch.allclose(R, torch.eye(3, dtype=R.dtype), atol=1e-7) else R


def lift_sh(sh: torch.Tensor, h: int = 128) -> tuple[torch.Tensor, torch.Tensor]:
    """Add the smallest per-channel constant that makes an SH light non-negative.

    Args:
        sh: (K, 3) light; the minimum is taken over a (h, 2h) grid of directions.

    Returns:
        (K, 3) lifted coefficients (only L_0 changes) and the (3,) constant radiance added.
    """
    check_shape(sh, ["K", 3], name="sh")
    dirs = equirect_directions(h, 2 * h, dtype=torch.float64)
    lo = radiance(sh.double(), world_to_light(dirs)).amin(dim=(0, 1))
    c = (-lo).clamp_min(0)
    out = sh.double().clone()
    out[0] += math.sqrt(4 * math.pi) * c
    return out.to(sh.dtype), c.to(sh.dtype)


def sh_world_image(sh: torch.Tensor, h: int = 128, negative: str = "clamp") -> tuple[torch.Tensor, float, torch.Tensor]:
    """Blender world image of an SH light in the world's light frame.

    Args:
        sh: (K, 3) coefficients (light frame of the world, i.e. after ``light_in_world``).
        h: image height (width 2h).
        negative: ``"clamp"`` or ``"lift"`` (module docstring).

    Returns:
        image (h, 2h, 3) float32 ≥ 0, the fraction of negative power, and the (K, 3)
        coefficients the image represents before clamping (lifted for ``"lift"``).
    """
    check_shape(sh, ["K", 3], name="sh")
    check_sh_count(sh, "sh")
    check_finite(sh, "sh")
    if negative not in _NEGATIVE:
        raise InputError(f"negative: expected one of {_NEGATIVE}, got {negative!r}")
    if negative == "lift":
        sh, _ = lift_sh(sh, max(h, 128))
    dirs = equirect_directions(h, 2 * h, dtype=torch.float64)
    img = radiance(sh.double(), world_to_light(dirs))
    # Pixels of an equirect row share one solid angle ∝ sin θ.
    sa = torch.sin(math.pi * (torch.arange(h, dtype=torch.float64) + 0.5) / h)[:, None, None]
    total = float((img.abs() * sa).sum())
    neg = float((img.clamp(max=0).abs() * sa).sum()) / total if total > 0 else 0.0
    return img.clamp_min(0).float(), neg, sh.float()


def envmap_world_image(env: torch.Tensor, R: torch.Tensor | None = None) -> torch.Tensor:
    """Blender world image of one of our lat-long maps, optionally seen from a rotated camera.

    Args:
        env: (H, W, 3) lat-long radiance (relightnet layout); relative to the camera when R is given.
        R: (3, 3) world→camera rotation: world radiance in direction d is ``env(R d)``.
            None: the map is already in the world frame.

    Returns:
        (H, W, 3) float32 in Blender's layout: an exact column roll for R = None and W
        divisible by 4, else bilinear resampling (u wraps, v clamps).
    """
    check_shape(env, ["H", "W", 3], name="env")
    check_finite(env, "env")
    h, w = env.shape[:2]
    if R is None and w % 4 == 0:
        return latlong_to_equirect(env.float())
    d = equirect_directions(h, w, dtype=torch.float64)
    if R is not None:
        d = d @ R.to(torch.float64).T
    uv = directions_to_latlong(d, h, w)
    x, y = uv[..., 0] - 0.5, (uv[..., 1] - 0.5).clamp(0, h - 1)
    x0, y0 = torch.floor(x), torch.floor(y).clamp(max=h - 2) if h > 1 else torch.zeros_like(y)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    j0, i0 = x0.long() % w, y0.long()
    j1, i1 = (j0 + 1) % w, (i0 + 1).clamp(max=h - 1)
    e = env.double()
    top = e[i0, j0] * (1 - fx) + e[i0, j1] * fx
    bot = e[i1, j0] * (1 - fx) + e[i1, j1] * fx
    return (top * (1 - fy) + bot * fy).float()


def _is_envmap(light) -> bool:
    if not isinstance(light, (str, os.PathLike)):
        return False
    p = Path(light)
    if p.suffix.lower() in _ENV_SUFFIXES:
        return True
    from ..light import preset_names

    return isinstance(light, str) and not p.suffix and len(p.parts) == 1 and light in preset_names()


def _read_env(light) -> torch.Tensor:
    from ..io import read_envmap
    from ..light import preset_envmap

    p = Path(light)
    if p.suffix.lower() in _ENV_SUFFIXES:
        if not p.is_file():
            raise InputError(f"{p}: no such environment map")
        return read_envmap(p)
    return preset_envmap(str(light))


def world_light(
    light,
    camera: Camera | None = None,
    light_frame: str = "camera",
    band_limit: bool = False,
    lmax: int = 2,
    size: int = 128,
    negative: str = "clamp",
) -> WorldLight:
    """Turn any relightnet light into a Blender world image.

    Args:
        light: a (K, 3) SH tensor, a light file (``.npz``/``.json``/``.npy``), an environment
            map (``.exr``/``.hdr``) or a preset name (its full map).
        camera: the render camera (one); used when ``light_frame="camera"``.
        light_frame: ``"camera"`` (relightnet's avatar convention) or ``"world"``.
        band_limit: use the order-``lmax`` SH reconstruction of an environment map instead
            of the full map (what relightnet's PRT renderer sees).
        lmax: SH order for projecting environment maps (stored SH keeps its own order).
        size: height of the reconstructed image of an SH light (width 2·size).
        negative: negative radiance of SH reconstructions: ``"clamp"`` or ``"lift"``.

    Returns:
        :class:`WorldLight`.

    Raises:
        InputError: unknown light / unreadable file / bad options; ShapeError: a light
        sequence (T, K, 3) or a wrong coefficient count.
    """
    from ..render import light_in_world

    R = _rotation(camera, light_frame)
    source = "tensor" if isinstance(light, torch.Tensor) else str(light)
    if _is_envmap(light):
        env = _read_env(light)
        sh_cam = project_envmap(env, lmax).float()
        sh_w = sh_cam if R is None else light_in_world(sh_cam, camera)[0]
        if not band_limit:
            return WorldLight(envmap_world_image(env, R), sh_w, "envmap", source)
    else:
        sh_cam = load_light(light)
        if sh_cam.dim() != 2:
            raise ShapeError(f"light {source}: expected one light (K, 3), got a sequence {tuple(sh_cam.shape)}")
        sh_w = sh_cam if R is None else light_in_world(sh_cam, camera)[0]
    if int(size) < 2:
        raise InputError(f"world size: expected >= 2 rows, got {size}")
    img, neg, sh_img = sh_world_image(sh_w, int(size), negative)
    return WorldLight(img, sh_img, "sh", source, neg)
