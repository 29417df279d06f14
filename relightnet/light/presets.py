"""Named and analytic lights.

Presets are the eight CC0 environment maps shipped in ``relightnet/data/envmaps``
(city, courtyard, forest, interior, night, studio, sunrise, sunset), projected to
SH of any order. Analytic lights: constant (ambient) radiance and a
directional light (a band-limited delta, or a von Mises–Fisher lobe).

Caching: projecting a 1024×512 map takes about half a second, so
:func:`preset_light` keeps the results for the shipped, read-only files in a
small ``functools.lru_cache`` keyed on ``(name, lmax)`` and hands out copies.
This is the only cache; user files are never cached.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import torch

from ..checks import InputError, check_finite
from ..names import envmap_dir, light_presets
from ..sh.basis import sh_basis, sh_count, sh_degrees
from ..sh.projection import project_envmap

__all__ = [
    "preset_names",
    "preset_path",
    "preset_envmap",
    "preset_light",
    "ambient_light",
    "directional_light",
    "side_light",
]


def _envmap_dir() -> Path:
    return envmap_dir()


def preset_names() -> list[str]:
    """Sorted names of the shipped environment-map presets (file stems of ``data/envmaps/*.exr``)."""
    return light_presets()


def preset_path(name: str) -> Path:
    """Path of a preset's environment map; :class:`InputError` listing the valid names if unknown."""
    names = preset_names()
    if name not in names:
        raise InputError(
            f"{name!r}: not a light file or preset name; presets are {', '.join(names)}"
        )
    return _envmap_dir() / f"{name}.exr"


def preset_envmap(name: str) -> torch.Tensor:
    """A preset's environment map: (H, W, 3) float32 linear radiance, world-frame lat-long."""
    from ..io.envmap import read_envmap

    return read_envmap(preset_path(name))


@functools.lru_cache(maxsize=32)
def _preset_light_cached(name: str, lmax: int) -> torch.Tensor:
    return project_envmap(preset_envmap(name), lmax)


def preset_light(name: str, lmax: int = 2) -> torch.Tensor:
    """SH light of a preset environment map.

    Args:
        name: one of :func:`preset_names`.
        lmax: SH order.

    Returns:
        (K, 3) float32 linear RGB radiance coefficients in the light frame
        (a fresh copy; results are cached per ``(name, lmax)``, see module doc).
    """
    sh_count(lmax)
    preset_path(name)  # validate the name before touching the cache
    return _preset_light_cached(name, int(lmax)).clone()


def _color(color, name: str = "color") -> torch.Tensor:
    c = torch.as_tensor(color, dtype=torch.float32).reshape(-1)
    if c.numel() == 1:
        c = c.expand(3)
    if c.numel() != 3:
        raise InputError(f"{name}: expected a scalar or 3 RGB values, got {c.numel()} values")
    check_finite(c, name)
    return c.clone()


def ambient_light(color=1.0, lmax: int = 2) -> torch.Tensor:
    """Constant radiance from every direction.

    A white (albedo 1) Lambertian surface under it has radiance ``color``
    everywhere (irradiance ``π · color``).

    Args:
        color: scalar or (3,) linear RGB radiance.
        lmax: SH order (only the DC term is non-zero).

    Returns:
        (K, 3) float32 coefficients: ``L_0 = √(4π) · color``, zeros elsewhere.
    """
    sh = torch.zeros(sh_count(lmax), 3)
    sh[0] = math.sqrt(4 * math.pi) * _color(color)
    return sh


def _vmf_band_factors(lmax: int, kappa: float) -> torch.Tensor:
    """Zonal SH factors of a normalised von Mises–Fisher lobe: I_{l+½}(κ)/I_{½}(κ)."""
    from scipy.special import ive

    f = [float(ive(l + 0.5, kappa) / ive(0.5, kappa)) for l in range(lmax + 1)]
    return torch.tensor(f, dtype=torch.float64)


def directional_light(direction, color=1.0, lmax: int = 2, sharpness: float | None = None) -> torch.Tensor:
    """A light from one direction, band-limited to order ``lmax``.

    With ``sharpness=None`` this is the SH projection of a delta light,
    ``L_k = Y_k(d) · color``: it is *band-limited*, i.e. a smooth lobe of
    width ~π/(lmax+1) with ringing (small negative radiance away from ``d``),
    not a point light. Irradiance from it is the order-lmax approximation of
    ``color · max(n·d, 0)``, so ``color`` is the irradiance it delivers to a
    surface facing it. With ``sharpness=κ > 0`` the delta is replaced by a
    normalised von Mises–Fisher lobe ``∝ exp(κ d·ω)`` of the same total power,
    whose band factors ``I_{l+½}(κ)/I_{½}(κ)`` damp the higher bands (smaller κ
    = wider, softer light, less ringing).

    Args:
        direction: (3,) direction *toward* the light, light frame (x toward the
            camera, y image right, z up); normalised here.
        color: scalar or (3,) linear RGB power (irradiance at normal incidence).
        lmax: SH order.
        sharpness: None for a band-limited delta, or the vMF concentration κ > 0.

    Returns:
        (K, 3) float32 coefficients.
    """
    d = torch.as_tensor(direction, dtype=torch.float64).reshape(-1)
    if d.numel() != 3:
        raise InputError(f"direction: expected 3 values (x, y, z in the light frame), got {d.numel()}")
    check_finite(d, "direction")
    n = d.norm()
    if n < 1e-12:
        raise InputError("direction: expected a non-zero vector")
    y = sh_basis(d / n, lmax, check=False)  # (K,)
    if sharpness is not None:
        if not (math.isfinite(sharpness) and sharpness > 0):
            raise InputError(f"sharpness: expected a positive finite concentration, got {sharpness!r}")
        y = y * _vmf_band_factors(lmax, float(sharpness))[sh_degrees(lmax)]
    return (y[:, None] * _color(color).double()[None, :]).float()


def side_light(direction, power: float = 3.0, ambient: float = 0.3, lmax: int = 2) -> torch.Tensor:
    """White light ``power · Y(d) + ambient`` on the l = 0 coefficient (``d`` normalised): a strong light
    from one direction over a little of everywhere, the lights of the real-photo side contrast
    (:mod:`relightnet.pipeline.photo_checks`) and of the training's novel lights
    (:func:`relightnet.model.round_trip.novel_lights`).

    ``power · Y(d)`` is :func:`directional_light` (a band-limited delta).

    Args:
        direction: (3,) toward the light, camera-relative light frame (x camera, y image right, z up).

    Returns:
        (K, 3) float32.
    """
    light = directional_light(direction, power, lmax)
    light[0] += ambient
    return light
