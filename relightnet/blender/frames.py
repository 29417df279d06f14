"""relightnet's world frame (y up) ⇄ Blender's (z up): the one place where they meet.

relightnet (docs/design.md, "Frames"): right-handed, +y up, the person faces +z, the default camera looks
along −z. Blender: right-handed, +z up, "front" is −y. The map is a +90° rotation about x,

    v_blender = (x, −z, y)        v_world = (x_b, z_b, −y_b),

so up stays up and the person faces Blender's front (−y). Cameras need nothing more: a
Blender camera object looks along its local −z with local +y up — the OpenGL view frame
relightnet uses — so its ``matrix_world`` is ``C @ view⁻¹`` (C the 4×4 form of the map).

Environment images. Blender's equirectangular world texture (Cycles'
``direction_to_equirectangular``) puts, for a Blender direction d_b,
``u = ½ − atan2(y_b, x_b)/2π`` and ``v = ½ + asin(z_b)/π`` (v up): the image centre looks
along +x_b and u grows toward −y_b. relightnet's lat-long maps look along −z_world = +y_b
at the centre with u growing toward +x_world = +x_b (:mod:`relightnet.sh.directions`).
Both put straight up on the top row, and ``u_blender = u_ours − ¼`` (mod 1): a Blender
world image is our lat-long map with its columns rolled left by W/4. The tests measure
this with Cycles (a camera looking along each axis sees the expected texel), and the
sphere test checks that the lit side is the one our renderer lights.
"""

from __future__ import annotations

import math

import torch

from ..checks import check_shape

__all__ = [
    "BLENDER_FROM_WORLD",
    "world_to_blender",
    "blender_to_world",
    "transform_to_blender",
    "equirect_directions",
    "latlong_to_equirect",
]

#: 3×3 matrix C with v_blender = C @ v_world (a +90° rotation about x).
BLENDER_FROM_WORLD = torch.tensor([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]], dtype=torch.float64)


def world_to_blender(v: torch.Tensor) -> torch.Tensor:
    """(..., 3) relightnet world points or directions → (..., 3) Blender ``(x, −z, y)``."""
    check_shape(v, ["...", 3], name="v")
    return torch.stack([v[..., 0], -v[..., 2], v[..., 1]], dim=-1)


def blender_to_world(v: torch.Tensor) -> torch.Tensor:
    """(..., 3) Blender points or directions → (..., 3) relightnet world ``(x_b, z_b, −y_b)``."""
    check_shape(v, ["...", 3], name="v")
    return torch.stack([v[..., 0], v[..., 2], -v[..., 1]], dim=-1)


def transform_to_blender(m: torch.Tensor) -> torch.Tensor:
    """A local→world rigid transform of relightnet → the same transform in Blender's world.

    Args:
        m: (..., 4, 4) matrices mapping an object's local frame to relightnet's world
            (for a camera: the inverse of its view matrix).

    Returns:
        (..., 4, 4) float64 ``C @ m`` — Blender's ``matrix_world`` (the local frame is kept).
    """
    check_shape(m, ["...", 4, 4], name="m")
    c = torch.eye(4, dtype=torch.float64, device=m.device)
    c[:3, :3] = BLENDER_FROM_WORLD.to(m.device)
    return c @ m.to(torch.float64)


def equirect_directions(h: int, w: int, dtype=torch.float32, device=None) -> torch.Tensor:
    """relightnet world directions of the pixel centres of a Blender equirectangular image.

    Row 0 is the top of the image as stored in files (straight up); the polar angle from
    Blender's +z is ``θ = π (i + ½)/H`` and the azimuth ``α = π − 2π (j + ½)/W`` with
    ``d_b = (sin θ cos α, sin θ sin α, cos θ)`` (module docstring).

    Returns:
        (H, W, 3) unit directions in relightnet's world frame.
    """
    if h < 1 or w < 1:
        raise ValueError(f"equirect size: expected H, W >= 1, got ({h}, {w})")
    theta = math.pi * (torch.arange(h, dtype=torch.float64, device=device) + 0.5) / h
    alpha = math.pi - 2 * math.pi * (torch.arange(w, dtype=torch.float64, device=device) + 0.5) / w
    st, ct = torch.sin(theta)[:, None], torch.cos(theta)[:, None]
    d_b = torch.stack([st * torch.cos(alpha)[None], st * torch.sin(alpha)[None], ct.expand(h, w)], dim=-1)
    return blender_to_world(d_b).to(dtype)


def latlong_to_equirect(env: torch.Tensor) -> torch.Tensor:
    """Re-index one of our lat-long maps as a Blender world image, exactly.

    Args:
        env: (H, W, C) relightnet lat-long map (world frame), W divisible by 4.

    Returns:
        (H, W, C) the same radiance in Blender's equirectangular layout (columns rolled by −W/4).
    """
    check_shape(env, ["H", "W", "C"], name="env")
    w = env.shape[1]
    if w % 4:
        raise ValueError(f"env: a quarter-turn roll needs a width divisible by 4, got {w}")
    return torch.roll(env, shifts=-(w // 4), dims=1)
