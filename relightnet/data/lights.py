"""Random SH lights for the synthetic data: projected env maps and procedural lights.

A light is drawn as a :class:`LightDraw` — a *base* light, already white-balanced, lifted
to non-negative irradiance and normalised to level 1 — plus the rotation, mirror flag and
level that turn it into the (K, 3) light of a sample (:func:`light_at`). Sequences keep
the draw and vary the angle and the level over time.

Sources (light frame: x toward the camera, y image right, z up):

- ``"hdri"``: a shipped env map of the split (``preset_light``), rotated about the up
  axis by a uniform angle and mirrored (y → −y) with probability ½;
- ``"sky_sun"``: a sun (a sharp von Mises–Fisher lobe, warmer when low) over a sky
  (ambient + a broad lobe from above, bluish) and a dim ground bounce from below;
- ``"lobes"``: one to three broad, near-white area-like lobes (key, fill, rim) biased
  toward the camera side, plus a little ambient;
- ``"fills"``: two or three broad coloured lobes from anywhere, plus ambient.

Normalisation (the exposure rule of the generator): the irradiance
``E(n) = Σ Â_l L_k Y_k(n)`` of an order-2 light of a strong sun can dip below zero on
the far side, so the smallest per-channel ambient that keeps E ≥ 2 % of its maximum over
all normals is added first (``ambient_lift``; the radiance itself may still ring
negative: lifting it to ≥ 0 everywhere would flatten the shading contrast two- to
three-fold, so occluded pixels can rarely get slightly negative shading — measured on 30
samples: 0.02 % of the pixels, down to −2.5 % of the maximum). Then the light is scaled
so that its *level* — the largest luminance of E over all normals — equals the sample's
drawn level (log-uniform in :data:`LEVEL_RANGE`). As pixel = albedo ⊙ (T·L) and the
unoccluded T·L is E, a white surface facing the brightest direction then shows about
``level`` (linear), and the sRGB image needs no further exposure (a subject's mean
luminance is then typically 0.05–0.35).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import torch

from ..checks import InputError
from ..color import LUMA, luminance
from ..light import ambient_light, directional_light, preset_light
from ..sh import fibonacci_sphere, irradiance, rotate_sh, rotate_sh_up
from .light_families import FAMILIES, family_light

__all__ = [
    "LIGHT_SOURCES",
    "LEVEL_RANGE",
    "LUMA",
    "LightDraw",
    "luminance",
    "light_level",
    "lift_irradiance",
    "mirror_sh",
    "white_balance",
    "synthetic_light",
    "sample_light",
    "light_at",
]

LIGHT_SOURCES = ("hdri", "sky_sun", "lobes", "fills", *FAMILIES)

#: Range of the light level (max luminance of the irradiance over all normals), log-uniform.
LEVEL_RANGE = (0.8, 2.0)


#: The normals a light's level is taken over: a fixed 256-point lattice (a constant, made on import).
LEVEL_NORMALS = fibonacci_sphere(256, dtype=torch.float64)[0]


def _normals() -> torch.Tensor:
    return LEVEL_NORMALS


def light_level(sh: torch.Tensor) -> float:
    """The level of a (K, 3) light: max over unit normals of the luminance of its irradiance."""
    E = irradiance(sh.double(), _normals(), check=False)
    return float(luminance(E).max())


def lift_irradiance(sh: torch.Tensor, floor: float = 0.02) -> tuple[torch.Tensor, torch.Tensor]:
    """Add the smallest per-channel ambient that keeps the irradiance above ``floor`` × its max.

    Ambient radiance ``a`` adds ``π a`` to the irradiance at every normal.

    Args:
        sh: (K, 3) light.
        floor: lowest irradiance allowed, relative to the channel's largest.

    Returns:
        the lifted (K, 3) light (float64) and the (3,) ambient radiance added.
    """
    sh = sh.double()
    lmax = math.isqrt(sh.shape[0]) - 1
    E = irradiance(sh, _normals(), check=False)  # (N, 3)
    lift = ((floor * E.amax(0).clamp_min(0) - E.amin(0)) / math.pi).clamp_min(0)
    return sh + ambient_light(lift, lmax).double(), lift


def mirror_sh(sh: torch.Tensor) -> torch.Tensor:
    """Mirror a (..., K, 3) light left–right (y_light → −y_light): negate the odd-in-y coefficients."""
    from ..sh import sh_basis

    K = sh.shape[-2]
    lmax = math.isqrt(K) - 1
    d = fibonacci_sphere(2 * K + 8, dtype=torch.float64)[0]
    Y = sh_basis(d, lmax, check=False)
    Ym = sh_basis(d * torch.tensor([1.0, -1.0, 1.0], dtype=torch.float64), lmax, check=False)
    sign = torch.sign((Y * Ym).sum(0)).to(sh.dtype)  # +1 even in y, −1 odd in y (real SH, no mixing)
    return sh * sign[:, None]


def white_balance(rng: np.random.Generator, strength: float = 0.08) -> np.ndarray:
    """(3,) RGB gains of unit luminance: a warm/cool shift plus a small green/magenta tint."""
    warm = rng.normal(0.0, strength)
    tint = rng.normal(0.0, strength / 3)
    g = np.exp(np.array([warm, 0.0, -warm]) + np.array([-0.5, 1.0, -0.5]) * tint)
    return g / float(np.dot(g, LUMA))


def _unit(elev: float, azim: float) -> list[float]:
    """Light-frame direction from elevation above the horizon and azimuth from the camera axis."""
    return [math.cos(elev) * math.cos(azim), math.cos(elev) * math.sin(azim), math.sin(elev)]


def _hsv(h: float, s: float, v: float) -> np.ndarray:
    import colorsys

    return np.array(colorsys.hsv_to_rgb(h % 1.0, s, v))


def synthetic_light(kind: str, rng: np.random.Generator, lmax: int = 2) -> tuple[torch.Tensor, dict]:
    """A random procedural light (unnormalised) and its parameters.

    Args:
        kind: ``"sky_sun"``, ``"lobes"`` or ``"fills"`` (module docstring).
        rng: the random generator.
        lmax: SH order.

    Returns:
        (K, 3) float64 light in the light frame, and a JSON-serialisable parameter dict.
    """
    if kind == "sky_sun":
        elev = rng.uniform(math.radians(5), math.radians(75))
        azim = rng.uniform(-math.pi, math.pi)
        low = 1 - math.sin(elev)
        sun_col = np.array([1.0, 1.0 - 0.25 * low, 1.0 - 0.55 * low])
        sun = rng.uniform(0.6, 3.0)  # sun irradiance relative to the sky's
        kappa = rng.uniform(40, 400)
        sky_col = np.array([0.55, 0.72, 1.0]) * rng.uniform(0.8, 1.2, 3)
        ground_col = np.array([0.5, 0.45, 0.38]) * rng.uniform(0.7, 1.3, 3)
        sh = directional_light(_unit(elev, azim), sun * sun_col, lmax, sharpness=kappa).double()
        sh += ambient_light(0.12 * sky_col, lmax).double()
        sh += directional_light([0, 0, 1], 0.35 * sky_col, lmax, sharpness=2.0).double()
        sh += directional_light([0, 0, -1], rng.uniform(0.05, 0.25) * ground_col, lmax, sharpness=2.0).double()
        params = {"sun_elevation_deg": math.degrees(elev), "sun_azimuth_deg": math.degrees(azim),
                  "sun_to_sky": sun, "sun_kappa": kappa}
    elif kind in ("lobes", "fills"):
        n = int(rng.integers(1, 4)) if kind == "lobes" else int(rng.integers(2, 4))
        sh = torch.zeros((lmax + 1) ** 2, 3, dtype=torch.float64)
        lobes = []
        for i in range(n):
            if kind == "lobes":
                azim = rng.normal(0.0, math.radians(50)) if i == 0 else rng.uniform(-math.pi, math.pi)
                elev = rng.uniform(math.radians(-10), math.radians(60))
                col = np.exp(rng.normal(0.0, 0.06, 3))
                power = 1.0 if i == 0 else rng.uniform(0.15, 0.7)
                kappa = rng.uniform(2.0, 20.0)
            else:
                azim = rng.uniform(-math.pi, math.pi)
                elev = rng.uniform(math.radians(-30), math.radians(70))
                col = _hsv(rng.uniform(), rng.uniform(0.35, 0.9), 1.0)
                power = rng.uniform(0.4, 1.0)
                kappa = rng.uniform(1.0, 10.0)
            sh += directional_light(_unit(elev, azim), power * col, lmax, sharpness=kappa).double()
            lobes.append({"elevation_deg": math.degrees(elev), "azimuth_deg": math.degrees(azim),
                          "color": [float(c) for c in col], "power": float(power), "kappa": float(kappa)})
        amb = rng.uniform(0.02, 0.15)
        sh += ambient_light(amb, lmax).double()
        params = {"lobes": lobes, "ambient": amb}
    else:
        raise InputError(f"synthetic light kind: expected one of {LIGHT_SOURCES[1:4]}, got {kind!r}")
    return sh, {k: float(v) if isinstance(v, float | np.floating) else v for k, v in params.items()}


@dataclass(frozen=True)
class LightDraw:
    """One drawn light, before rotation and level.

    Attributes:
        base: (K, 3) float64 light: white-balanced, irradiance lifted (module docstring), level 1.
        source: one of :data:`LIGHT_SOURCES`. hdri: env-map name (``"hdri"`` only).
        angle: rotation about the up axis (radians). mirror: mirrored left–right first.
        level: target level (see module docstring).
        info: JSON-serialisable description (source parameters, white balance, lift, scale).
    """

    base: torch.Tensor
    source: str
    hdri: str | None
    angle: float
    mirror: bool
    level: float
    info: dict = field(default_factory=dict)


def _draw_source(rng: np.random.Generator, synthetic_prob: float, mix: dict | None) -> str:
    """The light source of a sample: the legacy draw (``mix`` None) or one weighted by ``mix``."""
    if not mix:
        synthetic = bool(rng.uniform() < synthetic_prob)
        kind = ("sky_sun", "lobes", "fills")[int(rng.choice(3, p=[0.4, 0.4, 0.2]))]
        return kind if synthetic else "hdri"
    names = sorted(mix)
    p = np.array([float(mix[n]) for n in names])
    return names[int(rng.choice(len(names), p=p / p.sum()))]


def sample_light(rng: np.random.Generator, hdris, lmax: int = 2, synthetic_prob: float = 0.3,
                 mix: dict | None = None) -> LightDraw:
    """Draw a light: an env map of ``hdris`` or, with ``synthetic_prob``, a procedural one.

    Args:
        rng: the random generator (every draw is made in a fixed order).
        hdris: env-map names the split may use (``SynthConfig.hdris(split)``).
        lmax: SH order.
        synthetic_prob: probability of a procedural light (when ``mix`` is not given).
        mix: optional weights of the sources (:data:`LIGHT_SOURCES`), e.g.
            ``{"hdri": 0.3, "preetham": 0.2, "window": 0.2, ...}``; replaces ``synthetic_prob``.
    """
    hdris = tuple(hdris)
    if not hdris:
        raise InputError("sample_light: no env maps to choose from")
    kind = _draw_source(rng, synthetic_prob, mix)
    name = hdris[int(rng.integers(len(hdris)))]
    angle = float(rng.uniform(0.0, 2 * math.pi))
    mirror = bool(rng.uniform() < 0.5)
    gains = white_balance(rng)
    level = float(math.exp(rng.uniform(math.log(LEVEL_RANGE[0]), math.log(LEVEL_RANGE[1]))))
    if kind in FAMILIES:
        raw, params = family_light(kind, rng, lmax, hdris)
        source, hdri = kind, None
    elif kind != "hdri":
        raw, params = synthetic_light(kind, rng, lmax)
        source, hdri = kind, None
        if kind == "lobes":
            angle, mirror = 0.0, False  # the key light's frontal bias is in its azimuth
    else:
        raw, params, source, hdri = preset_light(name, lmax).double(), {}, "hdri", name
    sh = raw * torch.as_tensor(gains, dtype=torch.float64)[None]
    sh, lift = lift_irradiance(sh)
    scale = 1.0 / max(light_level(sh), 1e-12)
    info = {
        "source": source, "hdri": hdri, "params": params, "white_balance": [float(g) for g in gains],
        "ambient_lift": [float(x) for x in lift], "scale": scale,
    }
    return LightDraw(sh * scale, source, hdri, angle, mirror, level, info)


def light_at(draw: LightDraw, angle: float | None = None, level: float | None = None,
             tilt: torch.Tensor | None = None) -> torch.Tensor:
    """The (K, 3) float32 light of a draw: mirror, rotate about up, tilt, scale to the level.

    Args:
        draw: a :class:`LightDraw`.
        angle: rotation about the up axis (default ``draw.angle``).
        level: target level (default ``draw.level``).
        tilt: optional (3, 3) light-frame rotation applied last (camera pitch).

    Returns:
        (K, 3) float32: radiance ``L(ω) = base(M Rᵀ Tᵀ ω)`` × level (M the mirror, R the
        rotation about up, T the tilt).
    """
    sh = mirror_sh(draw.base) if draw.mirror else draw.base
    sh = rotate_sh_up(sh, draw.angle if angle is None else float(angle))
    if tilt is not None:
        sh = rotate_sh(sh, tilt.double())
    return (sh * (draw.level if level is None else float(level))).float()
