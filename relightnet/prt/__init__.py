"""Precomputed radiance transfer per vertex: ray-cast visibility, SH transport, interreflection.

``vertex_transport(verts, faces, normals, lmax=2, prt=PrtSettings(n_dirs=256, occlusion=True, bounces=0))``
returns (V, K) transport vectors ``T_k = ∫ V · max(n·ω, 0) · Y_k(ω) dω`` (no 1/π,
ω in the light frame), so that shading is ``T @ L`` for an SH light L (K, 3).
"""

from .interreflection import BounceOperator, bounce_operator, check_albedo, interreflect
from .mesh_checks import MeshWarning, check_mesh, check_normals, mesh_scale, nonmanifold_edge_count
from .refine import SHADOW_EDGE, refined_transport
from .settings import PrtSettings
from .transport import transport_directions, vertex_transport
from .visibility import (
    ENGINES,
    EmbreeEngine,
    MitsubaEngine,
    Open3DEngine,
    RayEngine,
    RayHits,
    VertexRays,
    available_engines,
    make_engine,
    vertex_rays,
    vertex_visibility,
)

__all__ = [
    "PrtSettings", "vertex_transport", "transport_directions", "refined_transport", "SHADOW_EDGE",
    "vertex_visibility", "vertex_rays", "VertexRays", "make_engine", "available_engines", "ENGINES",
    "RayEngine", "RayHits", "EmbreeEngine", "MitsubaEngine", "Open3DEngine",
    "BounceOperator", "bounce_operator", "interreflect", "check_albedo",
    "MeshWarning", "check_mesh", "check_normals", "mesh_scale", "nonmanifold_edge_count",
]
