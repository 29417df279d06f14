
import numpy as np
import pytest
import torch
import trimesh

from relightnet.checks import InputError, ShapeError
from relightnet.prt import RayEngine, available_engines, check_mesh, make_engine, vertex_visibility
from relightnet.prt.mesh_checks import MeshWarning
from relightnet.prt.visibility import EmbreeEngine, vertex_rays
from relightnet.sh import fibonacci_sphere


def sphere(sub=2, r=1.0, center=(0.0, 0.0, 0.0)):
    m = trimesh.creation.icosphere(subdivisions=sub, radius=r)
    v = torch.tensor(m.vertices, dtype=torch.float32)
    n = torch.nn.functional.normalize(v, dim=-1)
    return v + torch.tensor(center), torch.tensor(m.faces), n


def box(extent=4.0):
    m = trimesh.creation.box(extents=(extent,) * 3)  # outward winding
    return torch.tensor(m.vertices, dtype=torch.float32), torch.tensor(m.faces)


def merge(*meshes):
    vs, fs, off = [], [], 0
    for v, f in meshes:
        vs.append(v)
        fs.append(f + off)
        off += len(v)
    return torch.cat(vs), torch.cat(fs)


def brute_force_hits(verts, faces, o, d):
    """Closest hit by Möller–Trumbore over every triangle (float64 numpy): (prim, t)."""
    tri = verts[faces].astype(np.float64)
    p0, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    o, d = o.astype(np.float64)[:, None], d.astype(np.float64)[:, None]
    pv = np.cross(d, e2[None])
    det = np.einsum("rfc,fc->rf", pv, e1)
    inv = 1.0 / np.where(np.abs(det) < 1e-12, np.nan, det)
    s = o - p0[None]
    u = np.einsum("rfc,rfc->rf", s, pv) * inv
    q = np.cross(s, e1[None])
    v = np.einsum("rfc,rfc->rf", np.broadcast_to(d, q.shape), q) * inv
    t = np.einsum("rfc,fc->rf", q, e2) * inv
    ok = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    t = np.where(ok, t, np.inf)
    prim = np.where(np.isfinite(t.min(1)), t.argmin(1), -1)
    return prim, t.min(1)


def random_scene(seed=0):
    """Two overlapping spheres and a box: rays hit, graze and miss."""
    a = sphere(1, 1.0, (0.0, 0.0, 0.0))
    b = sphere(1, 0.6, (1.2, 0.3, 0.0))
    v, f = merge(a[:2], b[:2], box(1.0))
    g = np.random.default_rng(seed)
    o = g.uniform(-2.5, 2.5, (600, 3)).astype(np.float32)
    d = g.normal(size=(600, 3))
    d = (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)
    return v.numpy(), f.numpy(), o, d


def extra_engines():
    """Engines besides embree to cross-check: Mitsuba always (pinned in requirements.lock, LLVM 19
    installed by `make`), Open3D when someone installed it."""
    names = ["mitsuba"]
    if "open3d" in available_engines():
        names.append("open3d")
    return names


def test_embree_matches_brute_force():
    v, f, o, d = random_scene()
    prim_ref, t_ref = brute_force_hits(v, f, o, d)
    eng = make_engine(v, f, "embree")
    assert isinstance(eng, EmbreeEngine) and eng.name == "embree"
    np.testing.assert_array_equal(eng.occluded(o, d), prim_ref >= 0)
    hits = eng.intersect(o, d)
    np.testing.assert_array_equal(hits.prim >= 0, prim_ref >= 0)
    hit = prim_ref >= 0
    assert 50 < hit.sum() < 550  # the scene has both hits and misses
    np.testing.assert_allclose(hits.t[hit], t_ref[hit], rtol=1e-4, atol=1e-5)
    assert np.isinf(hits.t[~hit]).all()
    # Barycentrics rebuild the hit point on the hit triangle.
    tri = v[f[hits.prim[hit]]]
    b = np.stack([1 - hits.u[hit] - hits.v[hit], hits.u[hit], hits.v[hit]], 1)
    np.testing.assert_allclose(np.einsum("hj,hjc->hc", b, tri), o[hit] + hits.t[hit, None] * d[hit], atol=1e-4)


def test_other_engines_agree_with_embree():
    v, f, o, d = random_scene(1)
    ref = make_engine(v, f, "embree")
    occ, hits = ref.occluded(o, d), ref.intersect(o, d)
    for name in extra_engines():
        eng = make_engine(v, f, name)
        np.testing.assert_array_equal(eng.occluded(o, d), occ, err_msg=name)
        h = eng.intersect(o, d)
        np.testing.assert_array_equal(h.prim, hits.prim, err_msg=name)
        hit = h.prim >= 0
        np.testing.assert_allclose(h.t[hit], hits.t[hit], rtol=1e-4, err_msg=name)
        np.testing.assert_allclose(h.u[hit], hits.u[hit], atol=1e-4, err_msg=name)
        np.testing.assert_allclose(h.v[hit], hits.v[hit], atol=1e-4, err_msg=name)


def test_threads_do_not_change_answers():
    v, f, o, d = random_scene(2)
    one = EmbreeEngine(v, f, threads=1)
    many = EmbreeEngine(v, f, threads=3, chunk=50)
    np.testing.assert_array_equal(one.occluded(o, d), many.occluded(o, d))
    np.testing.assert_array_equal(one.intersect(o, d).prim, many.intersect(o, d).prim)
    assert one.occluded(o[:0], d[:0]).shape == (0,)


def test_convex_sphere_sees_its_whole_upper_hemisphere():
    v, f, n = sphere(2)
    dirs, _ = fibonacci_sphere(128)
    vis = vertex_visibility(v, f, n, dirs)
    assert vis.shape == (len(v), 128) and vis.dtype == torch.bool
    torch.testing.assert_close(vis, (n @ dirs.T) > 0, rtol=0, atol=0)


def test_point_inside_closed_box_sees_nothing():
    inner = sphere(1, 0.3)
    v, f = merge(inner[:2], box(4.0))
    n = torch.cat([inner[2], torch.nn.functional.normalize(v[len(inner[0]):], dim=-1)])
    vis = vertex_visibility(v, f, n, fibonacci_sphere(256)[0])
    assert not vis[: len(inner[0])].any()
    assert vis[len(inner[0]):].any()  # the box corners see out


def test_shadow_of_a_sphere_on_a_plane_vertex():
    s = sphere(3, 0.5, (0.0, 1.0, 0.0))
    pv = torch.tensor([[0.0, 0, 0], [1, 0, 0], [0, 0, 1], [-1, 0, 0], [0, 0, -1]])
    pf = torch.tensor([[0, 2, 1], [0, 3, 2], [0, 4, 3], [0, 1, 4]])
    v, f = merge(s[:2], (pv, pf))
    n = torch.cat([s[2], torch.tensor([0.0, 1, 0]).expand(5, 3)])
    dirs, _ = fibonacci_sphere(4096)
    vis = vertex_visibility(v, f, n, dirs)[len(s[0])]
    blocked = (dirs[:, 1] > 0) & ~vis
    # Directions within asin(r/d) = 30° of straight up are blocked, no others.
    cos_up = dirs[blocked, 1]
    assert cos_up.min() > np.cos(np.radians(30.5))
    assert ((dirs[:, 1] > np.cos(np.radians(29.5))) & vis).sum() == 0


def test_vertex_rays_cull_the_lower_hemisphere():
    v, f, n = sphere(1)
    dirs, _ = fibonacci_sphere(64)
    rays = vertex_rays(v, n, dirs, offset=1e-3)
    cos = n @ dirs.T
    assert len(rays.vertex) == int((cos > 0).sum())
    assert (rays.cosine > 0).all()
    scale = float((v.max(0).values - v.min(0).values).norm())
    np.testing.assert_allclose(rays.origins, (v + 1e-3 * scale * n).numpy()[rays.vertex], atol=1e-6)
    # Given the cosines (rows of a product over a larger mesh), the same rays.
    given = vertex_rays(v, n, dirs, offset=1e-3, cosines=cos)
    for k in ("vertex", "direction", "origins", "dirs", "cosine"):
        assert np.array_equal(getattr(given, k), getattr(rays, k))
    with pytest.raises(ShapeError, match="cosines"):
        vertex_rays(v, n, dirs, cosines=cos[:, :3])


def test_bad_inputs_raise_clear_errors():
    v, f, n = sphere(1)
    dirs, _ = fibonacci_sphere(16)
    with pytest.raises(InputError, match="empty"):
        vertex_visibility(v[:0], f[:0], n[:0], dirs)
    with pytest.raises(InputError, match="empty"):
        vertex_visibility(v, f[:0], n, dirs)
    with pytest.raises(InputError, match="indices"):
        vertex_visibility(v, f + 1, n, dirs)
    with pytest.raises(InputError, match="indices"):
        vertex_visibility(v, f - 1, n, dirs)
    with pytest.raises(InputError, match="integer"):
        vertex_visibility(v, f.float(), n, dirs)
    with pytest.raises(ShapeError, match="faces"):
        vertex_visibility(v, f[:, :2], n, dirs)
    with pytest.raises(ShapeError, match="normals"):
        vertex_visibility(v, f, n[:-1], dirs)
    with pytest.raises(InputError, match="unit"):
        vertex_visibility(v, f, 2 * n, dirs)
    with pytest.raises(InputError, match="unit"):
        vertex_visibility(v, f, n, 2 * dirs)
    bad = v.clone()
    bad[3, 1] = float("nan")
    with pytest.raises(InputError, match="NaN"):
        vertex_visibility(bad, f, n, dirs)
    with pytest.raises(InputError, match="coincide"):
        vertex_visibility(torch.zeros_like(v), f, n, dirs)
    with pytest.raises(InputError, match="engine"):
        vertex_visibility(v, f, n, dirs, engine="optix")
    with pytest.raises(InputError, match="offset"):
        vertex_visibility(v, f, n, dirs, offset=-1.0)


def test_non_manifold_mesh_warns_and_still_works():
    v, f, n = sphere(1)
    f3 = torch.cat([f, f[:1]])  # a duplicated face: its edges now have three faces
    with pytest.warns(MeshWarning, match="non-manifold"):
        vis = vertex_visibility(v, f3, n, fibonacci_sphere(32)[0])
    assert vis.any()
    with pytest.raises(InputError, match="non-manifold"):
        check_mesh(v, f3, manifold="error")


def test_engine_object_is_reused():
    v, f, n = sphere(1)
    eng = make_engine(v, f)
    assert isinstance(eng, RayEngine) and make_engine(v, f, eng) is eng
    dirs = fibonacci_sphere(32)[0]
    torch.testing.assert_close(vertex_visibility(v, f, n, dirs, engine=eng), vertex_visibility(v, f, n, dirs))
