"""Jobs beyond one process: Ray clusters for ``synth --ray`` and ``batch``.

The public names are what a caller needs to reach a cluster: :class:`RayOptions`, :func:`connect`
and :func:`default_workers`; the runners themselves (:mod:`.ray_synth`, :mod:`.ray_jobs`, the batch
runner) are handed their work by the floors above.

``ray`` is optional (``pip install 'relightnet[ray]'``) and imported only by the functions
of this package that need it (``connect``, :mod:`.ray_synth`, :mod:`.ray_jobs`); the batch
runner works locally without it.
"""

from .cluster import RayOptions, connect, default_workers

__all__ = [
    "RayOptions", "connect", "default_workers",
]
