"""Precomputed radiance transfer per vertex: ray-cast visibility, SH transport, interreflection.

``vertex_transport(verts, faces, normals, lmax=2, prt=PrtSettings(n_dirs=256, occlusion=True, bounces=0))``
returns (V, K) transport vectors ``T_k = ∫ V · max(n·ω, 0) · Y_k(ω) dω`` (no 1/π,
ω in the light frame), so that shading is ``T @ L`` for an SH light L (K, 3).

The public names are that entry point and its settings (:class:`PrtSettings`), the refined transport
of a dressed body, the directions and visibility it is built from, the ray engines
(:func:`make_engine`, :func:`available_engines`, :class:`RayEngine`), :func:`interreflect` and the mesh
check; the engines' classes, the bounce operator and the other mesh checks stay in their modules.
"""

from .interreflection import interreflect
from .mesh_checks import check_mesh
from .refine import refined_transport
from .settings import PrtSettings
from .transport import transport_directions, vertex_transport
from .visibility import RayEngine, available_engines, make_engine, vertex_visibility

__all__ = [
    "PrtSettings", "vertex_transport", "refined_transport", "transport_directions", "vertex_visibility", "make_engine",
    "available_engines", "RayEngine", "interreflect", "check_mesh",
]
