"""The app's light controls as plain functions: a point on the sphere ⇄ a direction, the sliders to a
light in words, a light from the chosen source, the diffuse-sphere preview.

Torch-free where it can be (the words are text); the light itself comes from :mod:`relightnet.sh`.
"""

from __future__ import annotations

import math

__all__ = ["LIGHT_SOURCES", "sphere_point_to_direction", "direction_to_sphere_point", "words_of",
           "hex_to_rgb", "light_of", "sphere_preview"]

#: Where the app's light comes from.
LIGHT_SOURCES = ("direction", "preset", "HDRI file", "plate")


def sphere_point_to_direction(x: float, y: float, size: int) -> tuple[float, float]:
    """Azimuth and elevation (degrees, camera terms) of the front-facing sphere point under pixel (x, y).

    The preview shows a unit sphere filling a ``size``-pixel square, seen from the camera; the
    point's normal is the direction the light comes from. A click outside the disc takes the
    nearest point of its rim (az ±90° at the sides).

    Returns:
        ``(az, el)``: az negative on the image's left, el positive at the top.
    """
    r = size / 2
    a, b = (x - r) / r, -(y - r) / r  # image right, up
    n = math.hypot(a, b)
    if n > 1:
        a, b = a / n, b / n
    front = math.sqrt(max(0.0, 1 - a * a - b * b))
    return math.degrees(math.atan2(a, front)), math.degrees(math.asin(max(-1.0, min(1.0, b))))


def direction_to_sphere_point(az: float, el: float, size: int) -> tuple[float, float] | None:
    """Pixel (x, y) of a direction on the preview sphere, or None when it faces away from the camera."""
    ca = math.cos(math.radians(el))
    x_l, y_l, z_l = ca * math.cos(math.radians(az)), ca * math.sin(math.radians(az)), math.sin(math.radians(el))
    if x_l < 0:
        return None
    r = size / 2
    return r + y_l * r, r - z_l * r


def hex_to_rgb(color: str) -> tuple[float, float, float]:
    """``#rrggbb`` (or ``rgb(r, g, b)`` / ``rgba(...)`` as browsers send it) → linear RGB (inverse sRGB)."""
    c = str(color).strip()
    if c.startswith("#") and len(c) in (4, 7):
        h = c[1:] if len(c) == 7 else "".join(ch * 2 for ch in c[1:])
        vals = [int(h[i:i + 2], 16) / 255 for i in (0, 2, 4)]
    elif c.startswith("rgb"):
        vals = [float(v) / 255 for v in c[c.index("(") + 1:c.index(")")].split(",")[:3]]
    else:
        vals = [1.0, 1.0, 1.0]

    def lin(v):
        return v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4

    return tuple(round(lin(min(max(v, 0.0), 1.0)), 4) for v in vals)


def words_of(az: float, el: float, size: float, power: float, color: str, ambient: float) -> str:
    """The sliders as a light in words (:mod:`relightnet.light.words`), which the CLI takes too."""
    r, g, b = hex_to_rgb(color)
    text = f"key:az={az:g},el={el:g},size={size:g},color={r:g}/{g:g}/{b:g},power={power:g}"
    return text + (f" + ambient:{ambient:g}" if ambient > 0 else "")


def light_of(source: str, words: str, preset: str | None, hdri_path: str | None, plate_path: str | None,
             fov: float = 60.0):
    """The (K, 3) light (order 2) of the chosen source.

    Raises:
        InputError: a missing file for the source, or a bad light (the message names it).
    """
    from ..checks import InputError
    from ..light import load_light
    from ..light.plate import load_plate_light

    if source == "direction":
        return load_light(words)
    if source == "preset":
        if not preset:
            raise InputError("preset: choose one")
        return load_light(preset)
    if source == "HDRI file":
        if not hdri_path:
            raise InputError("HDRI file: upload an .exr or .hdr environment map")
        return load_light(hdri_path)
    if source == "plate":
        if not plate_path:
            raise InputError("plate: upload a background photo")
        return load_plate_light(plate_path, hfov_deg=fov)
    raise InputError(f"light source {source!r}: expected one of {', '.join(LIGHT_SOURCES)}")


def sphere_preview(light, size: int = 160, az: float | None = None, el: float | None = None):
    """(S, S, 3) uint8: a white diffuse sphere under the light (sRGB, exposure: its 99th percentile at
    0.9), with a marker at the light's direction when it faces the camera."""
    import numpy as np

    from ..color import linear_to_srgb
    from ..light import render_sphere
    from ..light.visualize import auto_exposure

    img = render_sphere(light.float(), size)
    img = linear_to_srgb((img * auto_exposure(img)).clamp(0, 1))
    out = (img.numpy() * 255).round().astype(np.uint8)
    p = direction_to_sphere_point(az, el, size) if az is not None else None
    if p is not None:
        x, y = int(round(p[0])), int(round(p[1]))
        out[max(0, y - 3):y + 4, max(0, x - 3):x + 4] = (255, 60, 30)
    return out
