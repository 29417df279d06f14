"""The options of a PRT computation, as one frozen object that travels through the layers."""

from __future__ import annotations

from dataclasses import dataclass

from ..checks import InputError
from .visibility import RayEngine  # noqa: TC001 (the field's annotation)

__all__ = ["PrtSettings"]


@dataclass(frozen=True)
class PrtSettings:
    """How per-vertex transport is computed (:func:`~relightnet.prt.vertex_transport`,
    :func:`~relightnet.prt.refined_transport` and every job that renders with PRT).

    Args:
        n_dirs: directions D of the shared quadrature set (a spherical Fibonacci lattice).
        occlusion: cast rays (True) or use the unshadowed cosine lobe (False).
        bounces: diffuse interreflection bounces (integer >= 0; needs ``occlusion``).
        seed: rotation of the direction set (deterministic); None = unrotated.
        engine: ray engine name or instance (:func:`relightnet.prt.make_engine`).
        offset: ray origin offset along the normal, relative to the bounding-box diagonal.
        threads: ray-casting threads (None: the engine's default).

    Example:
        >>> PrtSettings(n_dirs=64, bounces=1)
        PrtSettings(n_dirs=64, occlusion=True, bounces=1, seed=0, engine='auto', offset=0.0001, threads=None)
    """

    n_dirs: int = 256
    occlusion: bool = True
    bounces: int = 0
    seed: int | None = 0
    engine: str | RayEngine = "auto"
    offset: float = 1e-4
    threads: int | None = None

    def __post_init__(self):
        if int(self.n_dirs) != self.n_dirs or self.n_dirs < 1:
            raise InputError(f"n_dirs: expected a positive integer, got {self.n_dirs!r}")
        if int(self.bounces) != self.bounces or self.bounces < 0:
            raise InputError(f"bounces: expected an integer >= 0, got {self.bounces!r}")
        if self.bounces and not self.occlusion:
            raise InputError("bounces >= 1 needs occlusion=True: light only bounces off surfaces that block it")
        if not self.offset >= 0:
            raise InputError(f"offset: expected a value >= 0, got {self.offset!r}")
