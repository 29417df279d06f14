"""Lights written in words, in camera terms: ``key:az=-40,el=30,size=20 + fill:az=60 + ambient:0.2``.

The grammar (accepted wherever a light is: ``--light``, :func:`relightnet.light.load_light`)::

    light  := term ( "+" term )*
    term   := kind [ ":" value | ":" param ( "," param )* ]
    kind   := key | fill | rim | light          a disc light (the names only say its role)
            | ambient                            the same radiance from every direction
    param  := name "=" value
    color  := r "/" g "/" b  |  one value        linear RGB

Parameters of a disc light (all optional):

- ``az`` azimuth in degrees as seen from the camera: 0 = from the camera, negative = from
  the image's left, positive = from its right, ±180 = from behind the person (default 0);
- ``el`` elevation in degrees: positive = from above, negative = from below (default 0);
- ``size`` the angular diameter of the source in degrees, 0 to 180 (default 0: a point
  light, band-limited like :func:`relightnet.light.directional_light`);
- ``color`` (or ``colour``) linear RGB, ``r/g/b`` or one grey value (default 1);
- ``power`` a scalar multiplier (default 1).

``ambient:V`` is ``ambient:power=V``; ``ambient`` takes ``color`` and ``power`` too.

Units: ``power · color`` is the irradiance the source delivers to a surface facing it (what
:func:`relightnet.light.directional_light` calls colour), whatever its size: a disc of
half-angle α has radiance ``power · color / Ω`` over its solid angle ``Ω = 2π(1 − cos α)``.
``ambient:V`` is a constant radiance V (a white surface under it shows ``π V``,
:func:`relightnet.light.ambient_light`).

Projection is exact (no sampling): the indicator of a cap of half-angle α is zonal, with
Legendre moments ``∫_{cos α}^1 P_l(t) dt = (P_{l−1}(cos α) − P_{l+1}(cos α)) / (2l + 1)``; turned
toward the direction d it gives ``L_{lm} = power · color · g_l · Y_{lm}(d)`` with
``g_l = ∫_{cos α}^1 P_l / (1 − cos α)``, the mean of P_l over the cap (g_0 = 1, g_l → 1 as α → 0).
"""

from __future__ import annotations

import math

import torch

from ..checks import InputError
from ..names import LIGHT_WORD_KINDS
from ..sh.basis import sh_basis, sh_count, sh_degrees

__all__ = ["LightTerm", "is_light_words", "parse_light_words", "disc_band_factors", "disc_light",
           "light_from_words", "camera_direction", "words_envmap"]

_DISC_PARAMS = ("az", "el", "size", "color", "colour", "power")
_AMBIENT_PARAMS = ("color", "colour", "power")


class LightTerm(dict):
    """One parsed term: ``kind`` and its parameters (``az``, ``el``, ``size`` in degrees,
    ``color`` a 3-tuple, ``power``), all filled with their defaults."""


def is_light_words(text) -> bool:
    """True when ``text`` is a string whose first term starts with a kind word (``key``, ``ambient``...)."""
    if not isinstance(text, str):
        return False
    head = text.split("+", 1)[0].split(":", 1)[0].strip().lower()
    return head in LIGHT_WORD_KINDS and (":" in text or "+" in text or text.strip().lower() == head)


def _number(value: str, name: str, where: str) -> float:
    try:
        x = float(value)
    except ValueError:
        raise InputError(f"{where}: {name}={value!r} is not a number") from None
    if not math.isfinite(x):
        raise InputError(f"{where}: {name}={value!r} must be finite")
    return x


def _color(value: str, where: str) -> tuple[float, float, float]:
    parts = value.split("/")
    if len(parts) not in (1, 3):
        raise InputError(f"{where}: color={value!r}: expected r/g/b or one grey value")
    c = [_number(p.strip(), "color", where) for p in parts]
    if min(c) < 0:
        raise InputError(f"{where}: color={value!r}: expected values >= 0 (linear RGB)")
    return (c[0],) * 3 if len(c) == 1 else (c[0], c[1], c[2])


def _in_range(x: float, lo: float, hi: float, name: str, where: str) -> float:
    if not lo <= x <= hi:
        raise InputError(f"{where}: {name}={x:g} is out of range; expected {lo:g} to {hi:g}")
    return x


def _parse_term(term: str, index: int) -> LightTerm:
    where = f"light term {index + 1} {term.strip()!r}"
    kind, _, rest = term.strip().partition(":")
    kind = kind.strip().lower()
    if kind not in LIGHT_WORD_KINDS:
        raise InputError(f"{where}: unknown kind {kind!r}; expected one of {', '.join(LIGHT_WORD_KINDS)}")
    out = LightTerm(kind=kind, az=0.0, el=0.0, size=0.0, color=(1.0, 1.0, 1.0), power=1.0)
    rest = rest.strip()
    if not rest:
        return out
    if "=" not in rest:  # ``ambient:0.2`` / ``key:2``: the power
        out["power"] = _in_range(_number(rest, "power", where), 0, math.inf, "power", where)
        return out
    allowed = _AMBIENT_PARAMS if kind == "ambient" else _DISC_PARAMS
    seen = set()
    for param in rest.split(","):
        name, eq, value = (s.strip() for s in param.partition("="))
        name = name.lower()
        if not eq or not value:
            raise InputError(f"{where}: {param.strip()!r} is not name=value")
        if name not in allowed:
            raise InputError(f"{where}: unknown parameter {name!r}; {kind} takes {', '.join(allowed)}")
        name = "color" if name == "colour" else name
        if name in seen:
            raise InputError(f"{where}: {name} is given twice")
        seen.add(name)
        if name == "color":
            out["color"] = _color(value, where)
            continue
        x = _number(value, name, where)
        limits = {"az": (-180, 180), "el": (-90, 90), "size": (0, 180), "power": (0, math.inf)}[name]
        out[name] = _in_range(x, *limits, name, where)
    return out


def parse_light_words(text: str) -> list[LightTerm]:
    """Parse a light in words (module docstring) into its terms.

    Raises:
        InputError: an empty light or a bad term; the message names the term (its number and text).
    """
    if not isinstance(text, str) or not text.strip():
        raise InputError("light: expected a light in words, e.g. 'key:az=-40,el=30 + ambient:0.2'")
    terms = text.split("+")
    for i, t in enumerate(terms):
        if not t.strip():
            raise InputError(f"light term {i + 1}: empty (two '+' in a row, or one at an end) in {text!r}")
    return [_parse_term(t, i) for i, t in enumerate(terms)]


def camera_direction(az_deg: float, el_deg: float, dtype=torch.float64) -> torch.Tensor:
    """The light-frame unit direction toward a light at azimuth/elevation in camera terms.

    Returns:
        (3,) ``(cos el cos az, cos el sin az, sin el)``: x toward the camera, y image right, z up.
    """
    az, el = math.radians(az_deg), math.radians(el_deg)
    return torch.tensor([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)], dtype=dtype)


def disc_band_factors(size_deg: float, lmax: int) -> torch.Tensor:
    """Per-band factors g_l of a uniform disc of angular diameter ``size_deg`` (module docstring).

    Returns:
        (lmax+1,) float64: the mean of the Legendre polynomial P_l over the cap; all 1 for size 0.
    """
    alpha = math.radians(size_deg) / 2
    u = 2 * math.sin(alpha / 2) ** 2  # 1 − cos α without cancellation
    if u < 0.1:
        # Small discs: P_l(1 − s) = Σ_k (−1)^k C(l,k) C(l+k,k) (s/2)^k, integrated over s ∈ [0, u]
        # and divided by u, term by term (no difference of nearly equal values).
        g = [sum((-1) ** k * math.comb(l, k) * math.comb(l + k, k) * (u / 2) ** k / (k + 1) for k in range(l + 1))
             for l in range(lmax + 1)]
        return torch.tensor(g, dtype=torch.float64)
    c = 1 - u
    p = [1.0, c]  # P_0, P_1, ... by the three-term recurrence, up to P_{lmax+1}
    for l in range(1, lmax + 1):
        p.append(((2 * l + 1) * c * p[l] - l * p[l - 1]) / (l + 1))
    g = [1.0] + [(p[l - 1] - p[l + 1]) / ((2 * l + 1) * u) for l in range(1, lmax + 1)]
    return torch.tensor(g, dtype=torch.float64)


def disc_light(direction, size_deg: float = 0.0, color=1.0, lmax: int = 2) -> torch.Tensor:
    """SH of a uniform disc light, exactly (module docstring).

    Args:
        direction: (3,) toward the light's centre, light frame; normalised here.
        size_deg: angular diameter in degrees (0: the band-limited point light).
        color: scalar or (3,) linear RGB irradiance delivered at normal incidence.
        lmax: SH order.

    Returns:
        (K, 3) float64 coefficients.
    """
    d = torch.as_tensor(direction, dtype=torch.float64).reshape(3)
    d = d / d.norm()
    c = torch.as_tensor(color, dtype=torch.float64).reshape(-1).expand(3)
    y = sh_basis(d, lmax, check=False) * disc_band_factors(size_deg, lmax)[sh_degrees(lmax)]
    return y[:, None] * c[None, :]


def light_from_words(text: str, lmax: int = 2) -> torch.Tensor:
    """Project a light in words to SH.

    Args:
        text: the light (module docstring), e.g. ``'key:az=-40,el=30,size=20,color=1/0.9/0.8,power=3 +
            fill:az=60,el=10,power=0.5 + ambient:0.2'``.
        lmax: SH order.

    Returns:
        (K, 3) float32 linear RGB radiance coefficients in the light frame.

    Raises:
        InputError: a bad term, named in the message.
    """
    sh = torch.zeros(sh_count(lmax), 3, dtype=torch.float64)
    for t in parse_light_words(text):
        rgb = t["power"] * torch.tensor(t["color"], dtype=torch.float64)
        if t["kind"] == "ambient":
            sh[0] += math.sqrt(4 * math.pi) * rgb
        else:
            sh += disc_light(camera_direction(t["az"], t["el"]), t["size"], rgb, lmax)
    return sh.float()


def words_envmap(text: str, h: int = 128) -> torch.Tensor:
    """The light in words drawn as a lat-long map (world frame, before the band limit), for viewing.

    Discs smaller than a pixel are drawn as one pixel of the same power.

    Returns:
        (H, 2H, 3) float32 linear radiance.
    """
    from ..sh.directions import latlong_directions
    from ..sh.frames import world_to_light

    dirs, sa = latlong_directions(h, 2 * h, dtype=torch.float64)
    dirs = world_to_light(dirs)
    env = torch.zeros(h, 2 * h, 3, dtype=torch.float64)
    for t in parse_light_words(text):
        rgb = t["power"] * torch.tensor(t["color"], dtype=torch.float64)
        if t["kind"] == "ambient":
            env += rgb
            continue
        cosang = dirs @ camera_direction(t["az"], t["el"])
        inside = cosang >= math.cos(math.radians(t["size"]) / 2)
        if not bool(inside.any()):
            inside = cosang == cosang.max()
        omega = float(sa[inside].sum())
        env[inside] += rgb / omega
    return env.float()
