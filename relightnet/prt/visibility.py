"""Per-vertex visibility by BVH ray casting, behind a small engine interface.

Engines (all wrap Intel Embree or an equivalent BVH; pick with ``engine=``):

- ``"embree"`` — `embreex` (pip only, in requirements.lock). One Embree scene; the
  rays are split into chunks traced by a thread pool (``embreex`` releases the
  GIL during its ray loop, so the threads run in parallel). The default.
- ``"mitsuba"`` — Mitsuba 3 ``scene.ray_test`` / ``ray_intersect_preliminary``
  on the ``llvm_ad_rgb`` variant (vectorised, multi-threaded by Dr.Jit). Faster
  per ray, but needs a system LLVM (Debian ``libllvm19`` and
  ``DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1``; with LLVM 15
  it crashes the process), so it is only used when asked for by name.
- ``"open3d"`` — ``open3d.t.geometry.RaycastingScene`` (needs Debian
  ``libusb-1.0-0`` to import).

``engine="auto"`` takes the first of ``embree``, ``open3d`` that imports; it
never picks Mitsuba on its own because a wrong LLVM kills the process instead of
raising.

Rays start at ``p + offset · diag · n`` (``diag`` = bounding-box diagonal of the
mesh, ``offset`` is therefore relative: 1e-4 is 0.2 mm on a 1.7 m body) and have
no far limit. Only directions in the upper hemisphere of the normal (n·ω > 0)
are cast; the others are reported occluded (their cosine weight is zero anyway).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import torch

from ..checks import InputError, check_shape, check_unit
from .mesh_checks import check_mesh, check_normals, mesh_scale

__all__ = [
    "ENGINES",
    "RayHits",
    "RayEngine",
    "EmbreeEngine",
    "MitsubaEngine",
    "Open3DEngine",
    "available_engines",
    "make_engine",
    "VertexRays",
    "vertex_rays",
    "vertex_visibility",
]

#: Ray engines by name, in the order ``engine="auto"`` tries them.
ENGINES = ("embree", "open3d", "mitsuba")
_AUTO_ORDER = ("embree", "open3d")


@dataclass(frozen=True)
class RayHits:
    """Closest hits of N rays (numpy, engine-independent).

    Attributes:
        prim: (N,) int64 hit triangle index, -1 for a miss.
        u, v: (N,) float32 barycentrics: hit = (1-u-v)·p0 + u·p1 + v·p2.
        t: (N,) float32 hit distance along the (unit) direction, inf for a miss.
    """

    prim: np.ndarray
    u: np.ndarray
    v: np.ndarray
    t: np.ndarray


class RayEngine:
    """A BVH over one triangle mesh answering batched ray queries.

    Subclasses implement :meth:`occluded` and :meth:`intersect` on float32
    numpy arrays ``origins (N, 3)``, ``dirs (N, 3)`` (unit directions).
    """

    name = "base"

    def occluded(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(N,) bool: True where the ray hits any triangle."""
        raise NotImplementedError

    def intersect(self, origins: np.ndarray, dirs: np.ndarray) -> RayHits:
        """Closest hit of every ray."""
        raise NotImplementedError


def _threads(threads: int | None) -> int:
    if threads is not None:
        return max(1, int(threads))
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


class EmbreeEngine(RayEngine):
    """Embree through `embreex`, traced in parallel chunks by a thread pool.

    Args:
        verts: (V, 3) float32 array. faces: (F, 3) integer array.
        threads: worker threads (default: the CPUs this process may use).
        chunk: rays per task; small enough to balance the threads.
    """

    name = "embree"

    def __init__(self, verts: np.ndarray, faces: np.ndarray, threads: int | None = None, chunk: int = 32768):
        from embreex import mesh_construction, rtcore_scene

        self._scene = rtcore_scene.EmbreeScene()
        self._verts = np.ascontiguousarray(verts, dtype=np.float32)
        self._faces = np.ascontiguousarray(faces, dtype=np.int32)
        mesh_construction.TriangleMesh(self._scene, self._verts, self._faces)
        self.threads, self.chunk = _threads(threads), int(chunk)
        # The scene commits (builds its BVH) on the first query: do it now, once.
        self._scene.run(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32), query="OCCLUDED")

    def _map(self, fn, n: int) -> None:
        bounds = list(range(0, n, self.chunk)) + [n]
        spans = list(zip(bounds[:-1], bounds[1:], strict=True))
        if self.threads == 1 or len(spans) == 1:
            for a, b in spans:
                fn(a, b)
            return
        with ThreadPoolExecutor(self.threads) as pool:
            list(pool.map(lambda ab: fn(*ab), spans))

    def occluded(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        o, d = _rays(origins, dirs)
        out = np.empty(len(o), dtype=bool)

        def work(a: int, b: int) -> None:
            out[a:b] = self._scene.run(o[a:b], d[a:b], query="OCCLUDED") != -1

        self._map(work, len(o))
        return out

    def intersect(self, origins: np.ndarray, dirs: np.ndarray) -> RayHits:
        o, d = _rays(origins, dirs)
        n = len(o)
        prim, u, v, t = np.empty(n, np.int64), np.empty(n, np.float32), np.empty(n, np.float32), np.empty(n, np.float32)

        def work(a: int, b: int) -> None:
            r = self._scene.run(o[a:b], d[a:b], query="INTERSECT", output=1)
            prim[a:b], u[a:b], v[a:b], t[a:b] = r["primID"], r["u"], r["v"], r["tfar"]

        self._map(work, n)
        t[prim < 0] = np.inf
        return RayHits(prim, u, v, t)


class Open3DEngine(RayEngine):
    """Open3D's ``RaycastingScene`` (Embree inside, its own thread pool)."""

    name = "open3d"

    def __init__(self, verts: np.ndarray, faces: np.ndarray, threads: int | None = None):
        import open3d as o3d

        self._o3d = o3d
        self._scene = o3d.t.geometry.RaycastingScene(nthreads=0 if threads is None else int(threads))
        self._scene.add_triangles(
            o3d.core.Tensor(np.ascontiguousarray(verts, np.float32)),
            o3d.core.Tensor(np.ascontiguousarray(faces, np.uint32)),
        )

    def _tensor(self, origins, dirs):
        o, d = _rays(origins, dirs)
        return self._o3d.core.Tensor(np.concatenate([o, d], axis=1))

    def occluded(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        return self._scene.test_occlusions(self._tensor(origins, dirs)).numpy().astype(bool)

    def intersect(self, origins: np.ndarray, dirs: np.ndarray) -> RayHits:
        r = self._scene.cast_rays(self._tensor(origins, dirs))
        prim = r["primitive_ids"].numpy().astype(np.int64)
        prim[prim == 0xFFFFFFFF] = -1
        uv = r["primitive_uvs"].numpy()
        return RayHits(prim, uv[:, 0].copy(), uv[:, 1].copy(), r["t_hit"].numpy().astype(np.float32))


_DEBIAN_LLVM19 = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


class MitsubaEngine(RayEngine):
    """Mitsuba 3 on a JIT variant (``llvm_ad_rgb`` is selected if no variant is set).

    ``DRJIT_LIBLLVM_PATH`` defaults to Debian's LLVM 19 when that file exists and
    the variable is unset (it must be set before Dr.Jit first loads).
    """

    name = "mitsuba"

    def __init__(self, verts: np.ndarray, faces: np.ndarray, threads: int | None = None):
        if os.path.exists(_DEBIAN_LLVM19):
            os.environ.setdefault("DRJIT_LIBLLVM_PATH", _DEBIAN_LLVM19)
        import mitsuba as mi

        if mi.variant() is None:
            mi.set_variant("llvm_ad_rgb")
        if not str(mi.variant()).startswith(("llvm_", "cuda_")):
            raise InputError(f"engine 'mitsuba' needs an llvm_* or cuda_* variant, Mitsuba is set to {mi.variant()!r}")
        if threads is not None:
            import drjit as dr

            dr.set_thread_count(int(threads))
        self._mi = mi
        mesh = mi.Mesh("prt", len(verts), len(faces), has_vertex_normals=False)
        params = mi.traverse(mesh)
        params["vertex_positions"] = mi.Float(np.ascontiguousarray(verts, np.float32).ravel())
        params["faces"] = mi.UInt32(np.ascontiguousarray(faces, np.uint32).ravel())
        params.update()
        self._scene = mi.load_dict({"type": "scene", "mesh": mesh})

    def _ray(self, origins, dirs):
        o, d = _rays(origins, dirs)
        mi = self._mi
        return mi.Ray3f(mi.Point3f(o.T), mi.Vector3f(d.T))

    def occluded(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        return np.asarray(self._scene.ray_test(self._ray(origins, dirs)), dtype=bool)

    def intersect(self, origins: np.ndarray, dirs: np.ndarray) -> RayHits:
        pi = self._scene.ray_intersect_preliminary(self._ray(origins, dirs))
        valid = np.asarray(pi.is_valid(), dtype=bool)
        prim = np.where(valid, np.asarray(pi.prim_index).astype(np.int64), -1)
        uv = np.asarray(pi.prim_uv)
        t = np.where(valid, np.asarray(pi.t, dtype=np.float32), np.float32(np.inf))
        return RayHits(prim, uv[0].astype(np.float32), uv[1].astype(np.float32), t.astype(np.float32))


_CLASSES = {"embree": EmbreeEngine, "open3d": Open3DEngine, "mitsuba": MitsubaEngine}
_MODULES = {"embree": "embreex", "open3d": "open3d", "mitsuba": "mitsuba"}


def _rays(origins: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    o = np.ascontiguousarray(origins, dtype=np.float32).reshape(-1, 3)
    d = np.ascontiguousarray(dirs, dtype=np.float32).reshape(-1, 3)
    if o.shape != d.shape:
        raise InputError(f"rays: origins {o.shape} and dirs {d.shape} differ")
    return o, d


def available_engines() -> list[str]:
    """Names of the engines whose Python package is installed (importability is not tried)."""
    import importlib.util

    return [e for e in ENGINES if importlib.util.find_spec(_MODULES[e]) is not None]


def make_engine(verts, faces, engine: str | RayEngine = "auto", threads: int | None = None) -> RayEngine:
    """Build a BVH over a mesh with the named engine.

    Args:
        verts: (V, 3) vertex positions. faces: (F, 3) vertex indices (validated).
        engine: ``"auto"``, ``"embree"``, ``"open3d"``, ``"mitsuba"``, or an engine
            object, which is returned unchanged (it must have been built on this mesh).
        threads: worker threads (engine default when None).

    Raises:
        InputError: unknown engine name, or no engine installed.
        ImportError: a named engine's package is not installed.
    """
    if isinstance(engine, RayEngine):
        return engine
    if engine not in ("auto",) + ENGINES:
        raise InputError(f"engine: expected 'auto' or one of {ENGINES}, got {engine!r}")
    v, f = check_mesh(verts, faces, manifold="ignore")
    v, f = v.numpy(), f.numpy()
    if engine != "auto":
        return _CLASSES[engine](v, f, threads=threads)
    errors = []
    for name in _AUTO_ORDER:
        try:
            return _CLASSES[name](v, f, threads=threads)
        except ImportError as e:
            errors.append(f"{name}: {e}")
    raise InputError("no ray engine available (pip install embreex): " + "; ".join(errors))


@dataclass(frozen=True)
class VertexRays:
    """The upper-hemisphere rays of every vertex for one shared direction set.

    Attributes:
        vertex: (N,) int64 vertex of each ray. direction: (N,) int64 direction index.
        origins: (N, 3) float32 offset ray origins. dirs: (N, 3) float32 world directions.
        cosine: (N,) float32 n·ω > 0.
        n_verts, n_dirs: V and D.
    """

    vertex: np.ndarray
    direction: np.ndarray
    origins: np.ndarray
    dirs: np.ndarray
    cosine: np.ndarray
    n_verts: int
    n_dirs: int


def vertex_rays(verts: torch.Tensor, normals: torch.Tensor, dirs: torch.Tensor, offset: float = 1e-4,
                scale: float | None = None, cosines: torch.Tensor | None = None) -> VertexRays:
    """Enumerate the rays (vertex, direction) with n·ω > 0, vertex-major.

    Args:
        verts: (V, 3) float32 (already validated). normals: (V, 3) unit.
        dirs: (D, 3) unit world-frame directions.
        offset: origin offset along the normal, relative to the bounding-box diagonal.
        scale: that diagonal (default: of ``verts``; give the whole mesh's when ``verts`` is a subset).
        cosines: (V, D) float32 ``normals @ dirs.T`` when already computed (rows of a product over the
            whole mesh, so that a vertex's rays do not depend on which others are in ``verts``); None
            computes it.
    """
    if not (offset >= 0 and np.isfinite(offset)):
        raise InputError(f"offset: expected a finite value >= 0, got {offset!r}")
    # torch: its gathers and nonzero are about twice as fast as numpy's fancy indexing here.
    d = dirs.detach().cpu().to(torch.float32).contiguous()
    if cosines is None:
        cos = normals @ d.T  # (V, D)
    else:
        cos = torch.as_tensor(cosines)
        check_shape(cos, [verts.shape[0], d.shape[0]], name="cosines")
    up = cos > 0
    vi, di = up.nonzero(as_tuple=True)
    org = verts + float(offset * (mesh_scale(verts) if scale is None else scale)) * normals
    return VertexRays(
        vertex=vi.numpy(),
        direction=di.numpy(),
        origins=org.index_select(0, vi).numpy(),
        dirs=d.index_select(0, di).numpy(),
        cosine=cos[up].numpy(),
        n_verts=verts.shape[0],
        n_dirs=d.shape[0],
    )


def vertex_visibility(
    verts,
    faces,
    normals,
    dirs,
    offset: float = 1e-4,
    engine: str | RayEngine = "auto",
    threads: int | None = None,
) -> torch.Tensor:
    """Which directions each vertex sees unoccluded.

    Args:
        verts: (V, 3) world-frame positions. faces: (F, 3) vertex indices.
        normals: (V, 3) unit world-frame normals.
        dirs: (D, 3) unit world-frame directions (map light-frame sets with
            :func:`relightnet.sh.light_to_world`).
        offset: ray origin offset along the normal, relative to the mesh's
            bounding-box diagonal.
        engine: see :func:`make_engine`. threads: worker threads.

    Returns:
        (V, D) bool, True where n·ω > 0 and the ray escapes the mesh; directions
        below the surface (n·ω ≤ 0) are False without being cast.
    """
    verts, faces = check_mesh(verts, faces)
    normals = check_normals(normals, verts.shape[0])
    dirs = torch.as_tensor(dirs)
    check_shape(dirs, ["D", 3], name="dirs")
    check_unit(dirs, name="dirs")
    rays = vertex_rays(verts, normals, dirs, offset)
    eng = make_engine(verts, faces, engine, threads)
    vis = np.zeros((rays.n_verts, rays.n_dirs), dtype=bool)
    vis[rays.vertex, rays.direction] = ~eng.occluded(rays.origins, rays.dirs)
    return torch.from_numpy(vis)
