"""Pictures of SH lights: a lit sphere, the lat-long reconstruction, previews of presets.

The sphere is a white (albedo 1) Lambertian ball seen by the default camera
(orthographic front view: world +y up, camera looking along −z, so visible
normals have n_z > 0). Its pixel value is the outgoing radiance
``E(n)/π`` with ``E = irradiance(sh, world_to_light(n))``: a constant light of
radiance c gives a sphere of value c, the same units as the lat-long map, so
both can share one exposure.
"""

from __future__ import annotations

import logging
import math
import os
from pathlib import Path

import torch
import torch.nn.functional as F

from ..checks import InputError, check_finite, check_sh_count, check_shape
from ..sh.frames import world_to_light
from ..sh.irradiance import irradiance
from ..sh.projection import sh_to_envmap

__all__ = ["sphere_normals", "render_sphere", "auto_exposure", "light_preview", "render_presets"]

logger = logging.getLogger(__name__)

_GAP = 4  # pixels between panels of a preview


def sphere_normals(
    size: int, view: str = "front", dtype=torch.float32, device=None
) -> tuple[torch.Tensor, torch.Tensor]:
    """World-frame normals of a unit sphere filling a size×size orthographic view.

    Pixel (row i, column j) looks at image-plane point ``x = 2(j+½)/S − 1``
    (right), ``y = 1 − 2(i+½)/S`` (up). ``view="front"`` is the default camera
    (looking along −z): the visible normal is ``(x, y, √(1 − x² − y²))``.
    ``view="back"`` is the camera turned 180° about the up axis (looking along
    +z from behind the subject): the normal is ``(−x, y, −√(1 − x² − y²))``.

    Returns:
        normals: (S, S, 3) unit normals (zero outside the disc); mask: (S, S) bool.
    """
    if int(size) != size or size < 1:
        raise InputError(f"size: expected a positive integer, got {size!r}")
    if view not in ("front", "back"):
        raise InputError(f"view: expected 'front' or 'back', got {view!r}")
    c = (torch.arange(size, dtype=torch.float64, device=device) + 0.5) * (2.0 / size) - 1.0
    y, x = -c[:, None].expand(size, size), c[None, :].expand(size, size)
    r2 = x * x + y * y
    mask = r2 < 1.0
    z = torch.sqrt((1.0 - r2).clamp_min(0.0))
    n = torch.stack([x, y, z], -1) if view == "front" else torch.stack([-x, y, -z], -1)
    n = torch.where(mask[..., None], n / n.norm(dim=-1, keepdim=True).clamp_min(1e-12), torch.zeros_like(n))
    return n.to(dtype), mask


def render_sphere(sh: torch.Tensor, size: int = 128, view: str = "front") -> torch.Tensor:
    """Render a white diffuse sphere under an SH light (default camera, front view).

    Args:
        sh: (K, 3) linear RGB light in the light frame.
        size: output height and width S.
        view: ``"front"`` (default camera) or ``"back"`` (seen from behind the
            subject, see :func:`sphere_normals`).

    Returns:
        (S, S, 3) linear radiance ``E(n)/π`` (albedo 1); 0 outside the sphere.
        Not clamped: a ringing band-limited light can give small negative values.
    """
    check_shape(sh, ["K", 3], name="sh")
    check_sh_count(sh, "sh")
    check_finite(sh, "sh")
    n, mask = sphere_normals(size, view, dtype=sh.dtype, device=sh.device)
    nl = world_to_light(n[mask])  # (M, 3) unit normals in the light frame
    img = torch.zeros(size, size, 3, dtype=sh.dtype, device=sh.device)
    img[mask] = irradiance(sh, nl, check=False) / math.pi
    return img


def auto_exposure(img: torch.Tensor, mask: torch.Tensor | None = None, target: float = 0.9, q: float = 0.99) -> float:
    """Scale putting the ``q`` quantile of the brightest channel at ``target``.

    Args:
        img: (H, W, 3) linear values.
        mask: (H, W) pixels to consider (all when None).

    Returns:
        A positive multiplier (1.0 when the image is black).
    """
    v = img.amax(-1)
    v = v[mask] if mask is not None else v.reshape(-1)
    if v.numel() == 0:
        return 1.0
    ref = torch.quantile(v.double(), q).item()
    return target / ref if ref > 1e-12 else 1.0


def _resize(img: torch.Tensor, h: int, w: int) -> torch.Tensor:
    """(H, W, 3) → (h, w, 3) with area averaging (down) or bilinear (up)."""
    x = img.permute(2, 0, 1)[None].float()
    if img.shape[0] >= h and img.shape[1] >= w:
        x = F.interpolate(x, size=(h, w), mode="area")
    else:
        x = F.interpolate(x, size=(h, w), mode="bilinear", align_corners=False)
    return x[0].permute(1, 2, 0)


def _hstack(panels: list[torch.Tensor]) -> torch.Tensor:
    h = max(p.shape[0] for p in panels)
    out = []
    for i, p in enumerate(panels):
        if p.shape[0] < h:
            pad = torch.zeros(h - p.shape[0], p.shape[1], 3, dtype=p.dtype)
            p = torch.cat([p, pad], 0)
        out.append(p)
        if i + 1 < len(panels):
            out.append(torch.zeros(h, _GAP, 3, dtype=p.dtype))
    return torch.cat(out, 1)


def light_preview(
    sh: torch.Tensor,
    size: int = 256,
    env: torch.Tensor | None = None,
    exposure: float | str = "auto",
    max_frames: int = 8,
) -> torch.Tensor:
    """An 8-bit sRGB picture of a light.

    Panels, left to right, separated by 4 black pixels: the lit sphere seen by
    the default camera (size×size), the same sphere seen from behind the subject
    (size×size, :func:`sphere_normals` ``view="back"``), the lat-long
    reconstruction of the SH light (size × 2·size, world frame, up at the top;
    its centre is −z, the direction the camera looks, i.e. light from behind the
    subject), and the original environment map when ``env`` is given (same size,
    area-averaged). For a sequence (T, K, 3) the panels are the front-view
    spheres of up to ``max_frames`` evenly spaced frames.

    Exposure: one linear multiplier for all panels. ``"auto"`` puts the 99th
    percentile of the spheres' brightest channel at 0.9, so dim and bright lights
    are both visible; a float is used as the multiplier. Values are clamped to
    [0, 1] after scaling and sRGB-encoded.

    Args:
        sh: (K, 3) or (T, K, 3) linear RGB light.
        size: sphere size S in pixels.
        env: optional (H, W, 3) lat-long radiance map the light came from.
        exposure: ``"auto"`` or a positive float.

    Returns:
        (S, W_total, 3) uint8 sRGB image.
    """
    from ..io.image import to_uint8

    sh = torch.as_tensor(sh)
    check_shape(sh, ["...", "K", 3], name="sh")
    if sh.dim() not in (2, 3):
        raise InputError(f"sh: expected (K, 3) or (T, K, 3), got {tuple(sh.shape)}")
    sh = sh.detach().float().cpu()
    if sh.dim() == 3:
        t = sh.shape[0]
        idx = torch.linspace(0, t - 1, min(t, max_frames)).round().long().unique()
        spheres = [render_sphere(sh[i], size) for i in idx.tolist()]
        _, mask = sphere_normals(size)
        panels = spheres
        ref = torch.stack(spheres)
        scale_mask = mask.expand(len(spheres), size, size)
    else:
        front, back = render_sphere(sh, size), render_sphere(sh, size, "back")
        _, mask = sphere_normals(size)
        ref, scale_mask = torch.stack([front, back]), mask.expand(2, size, size)
        panels = [front, back, sh_to_envmap(sh, h=size)]
        if env is not None:
            env = torch.as_tensor(env)
            check_shape(env, ["H", "W", 3], name="env")
            panels.append(_resize(env.clamp_min(0), size, 2 * size))
    if exposure == "auto":
        scale = auto_exposure(ref, scale_mask)
    else:
        try:
            scale = float(exposure)
        except (TypeError, ValueError):
            raise InputError(f"exposure: expected 'auto' or a positive number, got {exposure!r}") from None
        if not (math.isfinite(scale) and scale > 0):
            raise InputError(f"exposure: expected 'auto' or a positive number, got {exposure!r}")
    logger.debug("preview exposure scale %.4g", scale)
    img = _hstack([p.clamp_min(0) * scale for p in panels])
    return to_uint8(img, srgb=True)


def render_presets(out_dir: str | os.PathLike, size: int = 256, lmax: int = 2) -> list[Path]:
    """Write a preview PNG of every preset light (:func:`light_preview` with the original map).

    Args:
        out_dir: folder (created if missing); files are ``<name>.png``.
        size: sphere size in pixels.
        lmax: SH order of the projected lights.

    Returns:
        The paths written, in :func:`relightnet.light.preset_names` order.
    """
    from ..io.image import write_image
    from .presets import preset_envmap, preset_light, preset_names

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in preset_names():
        env = preset_envmap(name)
        sh = preset_light(name, lmax)
        path = write_image(out / f"{name}.png", light_preview(sh, size, env=env))
        logger.info("wrote %s", path)
        paths.append(path)
    return paths
