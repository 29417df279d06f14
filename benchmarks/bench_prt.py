"""PRT speed: visibility rays/s against Mitsuba 3 ``ray_test``, and vertex_transport totals.

Run: ``.venv/bin/python benchmarks/bench_prt.py [--repeat 7]`` (ANNY_CACHE_DIR as set up by make).

Mesh: the Anny default body (13,718 vertices, 27,420 triangles) in the rest pose,
rotated to the world frame (y up). Rays: every vertex × the upper hemisphere of a
D-direction Fibonacci set (D = 64, 256), origins offset along the normal — the
exact rays :func:`relightnet.prt.vertex_visibility` casts. Both engines trace the
same numpy arrays, timed from numpy in to numpy out, interleaved, medians.
Mitsuba runs when it imports (``pip install mitsuba``, Debian ``libllvm19``,
``DRJIT_LIBLLVM_PATH``; set here to the Debian path when that file exists).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
import warnings

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import median_ms, table  # noqa: E402

from relightnet.prt import PrtSettings, available_engines, vertex_transport
from relightnet.prt.transport import transport_directions  # noqa: E402
from relightnet.prt.visibility import EmbreeEngine, vertex_rays  # noqa: E402
from relightnet.sh import light_to_world  # noqa: E402

_LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


def load_mesh() -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, str]:
    """Anny rest-pose mesh in the world frame (y up, facing +z) with area-weighted normals."""
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    os.environ.setdefault("ANNY_CACHE_DIR", os.path.join(repo, ".cache", "anny"))
    try:
        import anny

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = anny.Anny()
        v = model.template_vertices.detach().float().cpu()
        f = model.get_triangular_faces().cpu()
        v = torch.stack([v[:, 0], v[:, 2], -v[:, 1]], -1)  # Anny z-up, facing -y -> y-up, facing +z
        name = "Anny default body"
    except Exception as e:  # pragma: no cover - only without the Anny cache
        import trimesh

        ico = trimesh.creation.icosphere(subdivisions=5)
        v, f = torch.tensor(ico.vertices, dtype=torch.float32), torch.tensor(ico.faces)
        name = f"icosphere (Anny unavailable: {type(e).__name__})"
    tri = v[f]
    fn = torch.linalg.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n = torch.zeros_like(v).index_add_(0, f.reshape(-1), fn.repeat_interleave(3, 0))
    return v.contiguous(), f.contiguous(), torch.nn.functional.normalize(n, dim=-1), name


def mitsuba_scene(v: np.ndarray, f: np.ndarray):
    """A Mitsuba ``llvm_ad_rgb`` scene holding the mesh, or None when Mitsuba is unavailable."""
    if os.path.exists(_LLVM):
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", _LLVM)
    try:
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb")
    except Exception as e:  # noqa: BLE001 - any failure means "no peer"
        print(f"Mitsuba unavailable ({type(e).__name__}: {e}); peer columns left empty\n")
        return None
    mesh = mi.Mesh("body", len(v), len(f), has_vertex_normals=False)
    p = mi.traverse(mesh)
    p["vertex_positions"] = mi.Float(v.ravel())
    p["faces"] = mi.UInt32(f.astype(np.uint32).ravel())
    p.update()
    return mi, mi.load_dict({"type": "scene", "mesh": mesh})


def peer_queries(peer, o: np.ndarray, d: np.ndarray):
    """Mitsuba's occlusion and closest-hit queries on numpy rays, numpy out."""
    mi, scene = peer

    def ray():
        return mi.Ray3f(mi.Point3f(o.T), mi.Vector3f(d.T))

    def test():
        return np.asarray(scene.ray_test(ray()), dtype=bool)

    def hit():
        pi = scene.ray_intersect_preliminary(ray())
        return np.asarray(pi.t), np.asarray(pi.prim_index), np.asarray(pi.prim_uv)

    return test, hit


def interleaved(fns: list, repeat: int) -> list[float]:
    """Median seconds of each function, run in turn ``repeat`` times after one warm-up each."""
    for fn in fns:
        fn()
    times = [[] for _ in fns]
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t0 = time.perf_counter()
            fn()
            times[i].append(time.perf_counter() - t0)
    return [statistics.median(t) for t in times]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    torch.set_num_threads(2)
    v, f, n, name = load_mesh()
    vn, fnp = v.numpy(), f.numpy().astype(np.int32)
    peer = mitsuba_scene(vn, fnp)
    t0 = time.perf_counter()
    ours = EmbreeEngine(vn, fnp)
    build_ms = (time.perf_counter() - t0) * 1e3
    print(f"mesh: {name}, {len(v)} vertices, {len(f)} triangles; engines installed: {available_engines()}; "
          f"our threads: {ours.threads}; embreex BVH build {build_ms:.1f} ms\n")

    rows = []
    for d in (64, 256):
        dl, _ = transport_directions(d, seed=0)
        rays = vertex_rays(v, n, light_to_world(dl))
        o, dd = rays.origins, rays.dirs
        nr = len(o)
        fns = [lambda o=o, dd=dd: ours.occluded(o, dd), lambda o=o, dd=dd: ours.intersect(o, dd)]
        if peer is not None:
            fns += list(peer_queries(peer, o, dd))
        t = interleaved(fns, args.repeat)
        agree = "—"
        if peer is not None:
            agree = f"{(ours.occluded(o, dd) == fns[2]()).mean() * 100:.3f}%"
        for q, (i, j) in (("occluded", (0, 2)), ("closest hit", (1, 3))):
            m = nr / t[j] / 1e6 if peer is not None else float("nan")
            rows.append([d, q, nr, nr / t[i] / 1e6, m, (nr / t[i]) / (nr / t[j]) if peer is not None else "—", agree])
    print(table(["dirs", "query", "rays (n·ω>0)", "ours embreex M rays/s", "Mitsuba M rays/s", "ours / Mitsuba",
                 "same answers"], rows))

    rows = []
    engines = ["auto"] + (["mitsuba"] if peer is not None else [])
    for d in (64, 256):
        for b in (0, 1):
            row = [d, b]
            for eng in engines:
                def job(d=d, b=b, eng=eng):
                    return vertex_transport(v, f, n, prt=PrtSettings(n_dirs=d, bounces=b, engine=eng))

                row.append(median_ms(job, repeat=max(3, args.repeat // 2)))
            rows.append(row)
    print("\nvertex_transport total (validation, BVH build, rays, projection, bounce), lmax 2:\n")
    print(table(["dirs", "bounces"] + [f"ms, engine={e}" for e in engines], rows))


if __name__ == "__main__":
    main()
