"""The Blender bridge's options that travel together: the world light's and Cycles' own."""

from __future__ import annotations

from dataclasses import dataclass

from ..checks import InputError
from .world import _NEGATIVE

__all__ = ["CyclesSettings", "WorldLightSettings"]


@dataclass(frozen=True)
class WorldLightSettings:
    """How :func:`~relightnet.blender.world_light` turns a light into a Blender world image.

    Args:
        light_frame: ``"camera"`` (relightnet's avatar convention) or ``"world"``.
        band_limit: use the order-``lmax`` SH reconstruction of an environment map instead of the
            full map (what relightnet's PRT renderer sees).
        lmax: SH order for projecting environment maps (stored SH keeps its own order).
        size: height of the reconstructed image of an SH light (width 2·size).
        negative: negative radiance of SH reconstructions: ``"clamp"`` or ``"lift"``.

    Example:
        >>> WorldLightSettings(light_frame="world").negative
        'clamp'
    """

    light_frame: str = "camera"
    band_limit: bool = False
    lmax: int = 2
    size: int = 128
    negative: str = "clamp"

    def __post_init__(self):
        if self.light_frame not in ("camera", "world"):
            raise InputError(f"light_frame: expected 'camera' or 'world', got {self.light_frame!r}")
        if self.negative not in _NEGATIVE:
            raise InputError(f"negative: expected one of {_NEGATIVE}, got {self.negative!r}")


@dataclass(frozen=True)
class CyclesSettings:
    """How Cycles renders a scene the bridge writes: samples per pixel, diffuse bounces, threads.

    Args:
        spp: samples per pixel (>= 1).
        bounces: diffuse bounces (>= 0).
        threads: render threads (None: all cores).

    Example:
        >>> CyclesSettings(spp=16).bounces
        4
    """

    spp: int = 64
    bounces: int = 4
    threads: int | None = None

    def __post_init__(self):
        if isinstance(self.spp, bool) or int(self.spp) != self.spp or self.spp < 1:
            raise InputError(f"spp: expected an integer >= 1, got {self.spp!r}")
        if isinstance(self.bounces, bool) or int(self.bounces) != self.bounces or self.bounces < 0:
            raise InputError(f"bounces: expected an integer >= 0, got {self.bounces!r}")
