"""Procedural light families beyond rotated env maps: skies, windows, mixtures.

The lights users meet are not rotations of a few env maps. These families widen what the
generator draws (every function returns an *unnormalised* (K, 3) float64 light in the light
frame — x toward the camera, y image right, z up — and a JSON-serialisable parameter dict;
:func:`relightnet.data.lights.sample_light` balances and normalises it):

- ``"preetham"``: a clear or hazy daylight sky with the Perez luminance distribution and the
  Preetham–Shirley–Smits (1999) turbidity fits for luminance and chromaticity, a sun whose
  colour follows the air mass, and a ground below the horizon that reflects the sky; with
  probability ¼ overcast (no sun, a high turbidity);
- ``"window"``: indoor light through one or two rectangular windows or area lights, a warm
  ceiling lamp sometimes, and a coloured room bounce;
- ``"mixture"``: an env map of the split plus a coloured lobe or a window, mixed at a random
  weight.

Radiance functions are sampled on one shared Fibonacci direction set and projected with
one matmul (:func:`relightnet.sh.project`); suns are vMF lobes (:func:`relightnet.light.directional_light`).
"""

from __future__ import annotations

import math

import numpy as np
import torch

from ..light import ambient_light, directional_light, preset_light
from ..sh import fibonacci_sphere, project, sh_basis

__all__ = ["FAMILIES", "family_light", "perez_sky", "preetham_zenith", "xyY_to_rgb"]

#: Families this module draws.
FAMILIES = ("preetham", "window", "mixture")

_N_DIRS = 2048

# Perez coefficients (A..E) as linear functions of turbidity T: rows (slope, offset), for
# luminance Y and chromaticities x, y (Preetham, Shirley & Smits, "A practical analytic model
# for daylight", SIGGRAPH 1999, appendix A.2).
_PEREZ = {
    "Y": ((0.1787, -1.4630), (-0.3554, 0.4275), (-0.0227, 5.3251), (0.1206, -2.5771), (-0.0670, 0.3703)),
    "x": ((-0.0193, -0.2592), (-0.0665, 0.0008), (-0.0004, 0.2125), (-0.0641, -0.8989), (-0.0033, 0.0452)),
    "y": ((-0.0167, -0.2608), (-0.0950, 0.0092), (-0.0079, 0.2102), (-0.0441, -1.6537), (-0.0109, 0.0529)),
}
# Zenith chromaticity: rows are the T², T and 1 polynomials in the sun's zenith angle (θ³, θ², θ, 1).
_ZENITH = {
    "x": ((0.00166, -0.00375, 0.00209, 0.0), (-0.02903, 0.06377, -0.03202, 0.00394),
          (0.11693, -0.21196, 0.06052, 0.25886)),
    "y": ((0.00275, -0.00610, 0.00317, 0.0), (-0.04214, 0.08970, -0.04153, 0.00516),
          (0.15346, -0.26756, 0.06670, 0.26688)),
}
_XYZ_TO_RGB = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])

#: The shared direction set (D, 3) float64 and its quadrature weights (D,): a constant, made on import.
_DIRS: tuple[torch.Tensor, torch.Tensor] = fibonacci_sphere(_N_DIRS, dtype=torch.float64)


def _directions() -> tuple[torch.Tensor, torch.Tensor]:
    """The shared direction set (D, 3) float64 and its quadrature weights (D,) (:data:`_DIRS`)."""
    return _DIRS


def _project(values: np.ndarray, lmax: int) -> torch.Tensor:
    """(D, 3) radiance on :func:`_directions` → (K, 3) float64 SH."""
    d, w = _directions()
    return project(torch.as_tensor(values, dtype=torch.float64), sh_basis(d, lmax, check=False), w)


def _unit(elev: float, azim: float) -> np.ndarray:
    return np.array([math.cos(elev) * math.cos(azim), math.cos(elev) * math.sin(azim), math.sin(elev)])


def xyY_to_rgb(x, y, Y) -> np.ndarray:  # noqa: N802 (colour-science spelling)
    """CIE xyY → linear sRGB (Rec. 709 primaries, D65). Arrays broadcast; returns (..., 3)."""
    x, y, Y = (np.asarray(v, dtype=np.float64) for v in (x, y, Y))
    y = np.maximum(y, 1e-6)
    xyz = np.stack([x * Y / y, Y, (1 - x - y) * Y / y], -1)
    return xyz @ _XYZ_TO_RGB.T


def perez_sky(cos_theta: np.ndarray, gamma: np.ndarray, coeffs) -> np.ndarray:
    """Perez et al.'s sky distribution F(θ, γ) = (1 + A e^{B / cos θ})(1 + C e^{Dγ} + E cos² γ).

    Args:
        cos_theta: (...) cosine of the view direction's zenith angle (> 0: above the horizon).
        gamma: (...) angle between the view direction and the sun (radians).
        coeffs: (A, B, C, D, E).

    Returns:
        (...) relative value.
    """
    a, b, c, d, e = coeffs
    ct = np.maximum(cos_theta, 1e-2)
    return (1 + a * np.exp(b / ct)) * (1 + c * np.exp(d * gamma) + e * np.cos(gamma) ** 2)


def preetham_zenith(turbidity: float, theta_sun: float) -> tuple[float, float, float]:
    """Zenith (x, y, Y) of the Preetham sky: chromaticity and luminance (kcd/m²) for a sun at zenith angle θ."""
    chi = (4.0 / 9.0 - turbidity / 120.0) * (math.pi - 2 * theta_sun)
    Y = (4.0453 * turbidity - 4.9710) * math.tan(chi) - 0.2155 * turbidity + 2.4192
    th = np.array([theta_sun**3, theta_sun**2, theta_sun, 1.0])
    tt = np.array([turbidity**2, turbidity, 1.0])
    x, y = (float(tt @ (np.array(_ZENITH[c]) @ th)) for c in ("x", "y"))
    return x, y, max(Y, 1e-3)


def _preetham(rng: np.random.Generator, lmax: int) -> tuple[torch.Tensor, dict]:
    overcast = bool(rng.uniform() < 0.25)
    turb = float(rng.uniform(6.0, 10.0) if overcast else rng.uniform(1.8, 7.0))
    elev = float(rng.uniform(math.radians(2), math.radians(85)))
    azim = float(rng.uniform(-math.pi, math.pi))
    theta_s = math.pi / 2 - elev
    sun_dir = _unit(elev, azim)
    d = _directions()[0].numpy()
    up = d[:, 2]
    gamma = np.arccos(np.clip(d @ sun_dir, -1, 1))
    coeffs = {c: [s * turb + o for s, o in _PEREZ[c]] for c in _PEREZ}
    zx, zy, zY = preetham_zenith(turb, theta_s)
    rel = {c: perez_sky(up, gamma, coeffs[c]) / perez_sky(np.array(1.0), np.array(theta_s), coeffs[c]) for c in _PEREZ}
    sky = xyY_to_rgb(zx * rel["x"], zy * rel["y"], zY * rel["Y"]).clip(0)
    if overcast:  # CIE overcast: brighter at the zenith, grey
        sky = np.outer(zY * (1 + 2 * np.maximum(up, 0)) / 3, np.ones(3)) * rng.uniform(0.9, 1.1, 3)
    sky *= (up > 0)[:, None]
    horiz = float((sky[:, 1] * np.maximum(up, 0)).sum() * 4 * math.pi / len(up))  # sky irradiance, G
    sun_ratio, sun = 0.0, np.zeros(3)
    if not overcast:
        m = 1.0 / (math.sin(elev) + 0.50572 * (math.degrees(elev) + 6.07995) ** -1.6364)  # air mass
        tau = np.array([0.045, 0.09, 0.20]) + 0.025 * (turb - 1)  # Rayleigh ∝ λ⁻⁴ plus haze
        trans = np.exp(-tau * m)
        sun_ratio = float(math.exp(rng.uniform(math.log(0.7), math.log(6.0))))  # sun / sky irradiance
        sun = sun_ratio * horiz * trans / trans[1]
    # The ground reflects what falls on it (sky and sun) as a uniform radiance from below.
    ground_col = np.array([0.45, 0.40, 0.33]) * rng.uniform(0.6, 1.4, 3) * rng.uniform(0.1, 0.35)
    values = sky + np.outer(up <= 0, ground_col * (horiz + sun * math.sin(elev)) / math.pi)
    sh = _project(values, lmax)
    if not overcast:
        sh += directional_light(sun_dir.tolist(), sun.tolist(), lmax, sharpness=3000.0).double()
    params = {"overcast": overcast, "turbidity": turb, "sun_elevation_deg": math.degrees(elev),
              "sun_azimuth_deg": math.degrees(azim), "sun_to_sky": sun_ratio}
    return sh, params


def _rect_mask(d: np.ndarray, elev: float, azim: float, half_w: float, half_h: float) -> np.ndarray:
    """Directions inside a window seen at (elev, azim) with angular half-sizes (radians)."""
    el = np.arcsin(np.clip(d[:, 2], -1, 1))
    az = np.arctan2(d[:, 1], d[:, 0])
    daz = (az - azim + math.pi) % (2 * math.pi) - math.pi
    return (np.abs(daz) * np.cos(el) < half_w) & (np.abs(el - elev) < half_h)


def _window(rng: np.random.Generator, lmax: int) -> tuple[torch.Tensor, dict]:
    d = _directions()[0].numpy()
    values = np.zeros_like(d)
    windows = []
    for _ in range(int(rng.integers(1, 3))):
        elev, azim = float(rng.uniform(math.radians(-5), math.radians(40))), float(rng.uniform(-math.pi, math.pi))
        hw = float(rng.uniform(math.radians(8), math.radians(40)))
        hh = float(rng.uniform(math.radians(8), math.radians(30)))
        daylight = bool(rng.uniform() < 0.7)
        col = (np.array([0.85, 0.95, 1.1]) if daylight else np.array([1.0, 0.78, 0.55])) * rng.uniform(0.9, 1.1, 3)
        power = float(rng.uniform(0.3, 1.0))
        inside = _rect_mask(d, elev, azim, hw, hh)
        values += np.outer(inside, power * col / max(inside.mean(), 1e-3))
        windows.append({"elevation_deg": math.degrees(elev), "azimuth_deg": math.degrees(azim),
                        "half_width_deg": math.degrees(hw), "half_height_deg": math.degrees(hh),
                        "daylight": daylight, "power": power})
    sh = _project(values, lmax)
    total = 4 * math.pi * sum(w["power"] for w in windows)  # ~ irradiance facing the windows
    lamp = bool(rng.uniform() < 0.4)
    if lamp:
        sh += directional_light([0.0, 0.0, 1.0], (rng.uniform(0.2, 1.0) * total * np.array([1.0, 0.72, 0.45])).tolist(),
                                lmax, sharpness=float(rng.uniform(3, 15))).double()
    wall = np.array([rng.uniform(0.6, 1.0), rng.uniform(0.6, 1.0), rng.uniform(0.6, 1.0)])
    bounce = float(math.exp(rng.uniform(math.log(0.05), math.log(0.6))))  # room bounce / window irradiance
    sh += ambient_light((bounce * total * wall / math.pi).tolist(), lmax).double()
    sh += directional_light([0.0, 0.0, -1.0], (0.5 * bounce * total * wall).tolist(), lmax, sharpness=2.0).double()
    return sh, {"windows": windows, "lamp": lamp, "bounce": bounce}


def _mixture(rng: np.random.Generator, lmax: int, hdris) -> tuple[torch.Tensor, dict]:
    name = hdris[int(rng.integers(len(hdris)))]
    env = preset_light(name, lmax).double()
    env = env / max(float(env[0].mean()), 1e-9)
    if rng.uniform() < 0.5:
        other, p = _window(rng, lmax)
        kind = "window"
    else:
        elev, azim = float(rng.uniform(math.radians(-20), math.radians(70))), float(rng.uniform(-math.pi, math.pi))
        col = np.array([rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0)])
        other = directional_light(_unit(elev, azim).tolist(), col.tolist(), lmax,
                                  sharpness=float(rng.uniform(2, 40))).double()
        kind, p = "lobe", {"elevation_deg": math.degrees(elev), "azimuth_deg": math.degrees(azim),
                           "color": col.tolist()}
    other = other / max(float(other[0].mean()), 1e-9)
    w = float(rng.uniform(0.2, 0.8))
    angle = float(rng.uniform(0, 2 * math.pi))
    from ..sh import rotate_sh_up

    sh = (1 - w) * rotate_sh_up(env, angle) + w * other
    return sh, {"hdri": name, "hdri_rotation_deg": math.degrees(angle), "other": kind, "other_params": p,
                "weight": w}


def family_light(kind: str, rng: np.random.Generator, lmax: int = 2, hdris=()) -> tuple[torch.Tensor, dict]:
    """A random light of one of :data:`FAMILIES` (unnormalised).

    Args:
        kind: family name.
        rng: the random generator (draws in a fixed order).
        lmax: SH order.
        hdris: env-map names the split may use (``"mixture"`` only).

    Returns:
        (K, 3) float64 light in the light frame, and a JSON-serialisable parameter dict.
    """
    if kind == "preetham":
        return _preetham(rng, lmax)
    if kind == "window":
        return _window(rng, lmax)
    if kind == "mixture":
        return _mixture(rng, lmax, tuple(hdris))
    from ..checks import InputError

    raise InputError(f"light family: expected one of {FAMILIES}, got {kind!r}")
