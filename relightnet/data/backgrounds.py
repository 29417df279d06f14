"""Backgrounds for the composited input: procedural images and defocused views of env maps.

- :func:`procedural_background`: a smooth two- or three-colour gradient, plus optionally
  low-frequency colour noise and blurred colour blobs, scaled to a given mean luminance.
- :func:`envmap_background`: what the sample's camera would see of a lat-long env map
  behind the person (pinhole rays through every pixel, rotated into the env map's frame),
  defocused by a Gaussian blur. When the env map is the one that lights the sample, the
  rotation is the light's (so the background agrees with the lighting) and the gain is the
  light's: pixel = π · gain · radiance, because the subject's pixels are albedo · E (no 1/π)
  and a white Lambertian surface shows radiance E/π.
"""

from __future__ import annotations

import colorsys
import math

import numpy as np
import torch
import torch.nn.functional as F

from ..color import luminance
from ..sh import directions_to_latlong, light_to_world, world_to_light

__all__ = ["BACKGROUND_KINDS", "procedural_background", "envmap_background", "gaussian_blur"]

BACKGROUND_KINDS = ("procedural", "envmap")


def gaussian_blur(img: torch.Tensor, sigma: float) -> torch.Tensor:
    """Separable Gaussian blur of an (H, W, C) image (reflect padding); sigma in pixels."""
    if sigma <= 0.3:
        return img
    r = max(1, int(math.ceil(3 * sigma)))
    x = torch.arange(-r, r + 1, dtype=img.dtype)
    k = torch.exp(-0.5 * (x / sigma) ** 2)
    k = k / k.sum()
    c = img.shape[-1]
    t = img.permute(2, 0, 1)[None]  # (1, C, H, W)
    r = min(r, t.shape[-1] - 1, t.shape[-2] - 1)
    k = k[len(k) // 2 - r: len(k) // 2 + r + 1]
    k = k / k.sum()
    t = F.conv2d(F.pad(t, (r, r, 0, 0), mode="reflect"), k.view(1, 1, 1, -1).expand(c, 1, 1, -1), groups=c)
    t = F.conv2d(F.pad(t, (0, 0, r, r), mode="reflect"), k.view(1, 1, -1, 1).expand(c, 1, -1, 1), groups=c)
    return t[0].permute(1, 2, 0).contiguous()


def _color(rng: np.random.Generator) -> torch.Tensor:
    s = rng.uniform(0.0, 0.7) if rng.uniform() < 0.7 else rng.uniform(0.0, 0.15)
    rgb = np.array(colorsys.hsv_to_rgb(rng.uniform(), s, rng.uniform(0.2, 1.0)))
    return torch.as_tensor(rgb ** 2.2, dtype=torch.float32)


def procedural_background(rng: np.random.Generator, res: int, level: float) -> tuple[torch.Tensor, dict]:
    """A random smooth background.

    Args:
        rng: the random generator (all draws in a fixed order).
        res: side in pixels.
        level: target mean luminance (linear).

    Returns:
        (res, res, 3) float32 linear image and a JSON-serialisable description.
    """
    c = [_color(rng) for _ in range(3)]
    ang = rng.uniform(0, 2 * math.pi)
    three = bool(rng.uniform() < 0.4)
    use_noise, use_blobs = bool(rng.uniform() < 0.5), bool(rng.uniform() < 0.5)
    n_blobs = int(rng.integers(2, 12))
    noise_res = int(rng.integers(3, 10))
    noise_amp = rng.uniform(0.1, 0.5)
    noise = torch.as_tensor(rng.uniform(-1, 1, (1, 3, noise_res, noise_res)), dtype=torch.float32)
    blobs = [(rng.uniform(0, 1, 2), rng.uniform(0.05, 0.35), _color(rng)) for _ in range(n_blobs)]
    blur = rng.uniform(0.0, 0.03) * res
    y, x = torch.meshgrid(torch.linspace(0, 1, res), torch.linspace(0, 1, res), indexing="ij")
    t = (math.cos(ang) * (x - 0.5) + math.sin(ang) * (y - 0.5)) / math.sqrt(0.5) * 0.5 + 0.5
    t = t.clamp(0, 1)[..., None]
    if three:
        img = torch.where(t < 0.5, c[0] + (c[1] - c[0]) * 2 * t, c[1] + (c[2] - c[1]) * (2 * t - 1))
    else:
        img = c[0] + (c[1] - c[0]) * t
    if use_noise:
        up = F.interpolate(noise, size=(res, res), mode="bicubic", align_corners=True)[0].permute(1, 2, 0)
        img = img * (1 + noise_amp * up)
    if use_blobs:
        for centre, rad, col in blobs:
            d2 = (x - float(centre[0])) ** 2 + (y - float(centre[1])) ** 2
            w = torch.exp(-0.5 * d2 / rad**2)[..., None]
            img = img * (1 - 0.8 * w) + 0.8 * w * col
    img = gaussian_blur(img.clamp_min(0.0), blur)
    mean = float(luminance(img).mean())
    img = img * (level / max(mean, 1e-6))
    desc = {"kind": "procedural", "three_colors": three, "noise": use_noise, "blobs": use_blobs,
            "blur_px": blur, "level": level}
    return img.float(), desc


def envmap_background(env: torch.Tensor, intrinsics, res: int, light_to_env: torch.Tensor, gain,
                      blur_px: float = 0.0) -> torch.Tensor:
    """A defocused pinhole view of a lat-long env map.

    Args:
        env: (He, We, 3) linear lat-long radiance (world frame, :mod:`relightnet.sh.directions`).
        intrinsics: ``(fx, fy, cx, cy)`` of the camera, pixels (the camera's rotation is I).
        res: image side.
        light_to_env: (3, 3) rotation taking a light-frame direction of the camera to the
            light-frame direction of the env map it sees (for a light ``L(ω) = base(Q ω)``, Q).
        gain: (3,) or float multiplier (e.g. π · light scale · white balance).
        blur_px: Gaussian defocus sigma in pixels.

    Returns:
        (res, res, 3) float32 linear image.
    """
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    c = torch.arange(res, dtype=torch.float64) + 0.5
    v, u = torch.meshgrid(c, c, indexing="ij")
    d = torch.stack([(u - cx) / fx, -(v - cy) / fy, -torch.ones_like(u)], -1)
    d = d / d.norm(dim=-1, keepdim=True)
    w = light_to_world(world_to_light(d) @ light_to_env.double().T)
    He, We = env.shape[:2]
    uv = directions_to_latlong(w, He, We)
    grid = torch.stack([uv[..., 0] / We * 2 - 1, uv[..., 1] / He * 2 - 1], -1).float()[None]
    img = F.grid_sample(env.permute(2, 0, 1)[None].float(), grid, mode="bilinear", padding_mode="border",
                        align_corners=False)[0].permute(1, 2, 0)
    img = img.clamp_min(0.0) * torch.as_tensor(gain, dtype=torch.float32)
    return gaussian_blur(img, blur_px).float()
