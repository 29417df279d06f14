import math

import pytest
import torch
import trimesh

from relightnet.checks import InputError, ShapeError
from relightnet.prt import PrtSettings, transport_directions, vertex_transport
from relightnet.sh import fibonacci_sphere, sh_basis, world_to_light
from relightnet.sh.irradiance import cosine_lobe_per_coeff

Y0 = 0.5 / math.sqrt(math.pi)
C1 = math.sqrt(3 / (4 * math.pi))


def sphere(sub=2, r=1.0, center=(0.0, 0.0, 0.0)):
    m = trimesh.creation.icosphere(subdivisions=sub, radius=r)
    v = torch.tensor(m.vertices, dtype=torch.float32)
    return v + torch.tensor(center), torch.tensor(m.faces), torch.nn.functional.normalize(v, dim=-1)


def closed_form(normals, lmax=2):
    """Unshadowed transport Â_l Y_k(n), n in the world frame."""
    return cosine_lobe_per_coeff(lmax) * sh_basis(world_to_light(normals), lmax)


def plane_under_sphere(height=1.0, r=0.5):
    s = sphere(3, r, (0.0, height, 0.0))
    pv = torch.tensor([[0.0, 0, 0], [1, 0, 0], [0, 0, 1], [-1, 0, 0], [0, 0, -1]])
    pf = torch.tensor([[0, 2, 1], [0, 3, 2], [0, 4, 3], [0, 1, 4]]) + len(s[0])
    v = torch.cat([s[0], pv])
    f = torch.cat([s[1], pf])
    n = torch.cat([s[2], torch.tensor([0.0, 1, 0]).expand(5, 3)])
    return v, f, n, len(s[0])


def test_unoccluded_transport_is_the_closed_form():
    g = torch.Generator().manual_seed(0)
    n = torch.nn.functional.normalize(torch.randn(300, 3, generator=g), dim=-1)
    v, f, _ = sphere(0)
    verts = torch.randn(300, 3, generator=g)
    T = vertex_transport(verts, f, n, prt=PrtSettings(n_dirs=1024, occlusion=False))
    assert T.shape == (300, 9) and T.dtype == torch.float32
    assert (T - closed_form(n)).abs().max() <= 1e-3


def test_convex_sphere_is_never_shadowed():
    v, f, n = sphere(2)
    T = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=1024, occlusion=True))
    assert (T - closed_form(n)).abs().max() <= 1e-3
    torch.testing.assert_close(T, vertex_transport(v, f, n, prt=PrtSettings(n_dirs=1024, occlusion=False)), atol=1e-5,
                               rtol=0)


def test_point_inside_a_closed_box_receives_nothing():
    inner = sphere(1, 0.3)
    bx = trimesh.creation.box(extents=(4.0, 4.0, 4.0))
    bv = torch.tensor(bx.vertices, dtype=torch.float32)
    v = torch.cat([inner[0], bv])
    f = torch.cat([inner[1], torch.tensor(bx.faces) + len(inner[0])])
    n = torch.cat([inner[2], torch.nn.functional.normalize(bv, dim=-1)])
    T = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=256))
    assert T[: len(inner[0])].abs().max() == 0
    assert T[len(inner[0]):, 0].min() > 0  # the outside of the box is lit


def test_plane_under_sphere_matches_the_analytic_shadow():
    v, f, n, i = plane_under_sphere(height=1.0, r=0.5)
    cos_a = math.sqrt(1 - 0.5**2)  # shadow cone half-angle asin(r / d)
    # DC: Y0 ∫_{unblocked} cosθ dω = Y0 π cos²α; up band (Y2 = C1·z_light = C1·y_world): C1 (2π/3) cos³α.
    want = torch.tensor([Y0 * math.pi * cos_a**2, C1 * 2 * math.pi / 3 * cos_a**3])
    Ts = torch.stack([vertex_transport(v, f, n, lmax=2, prt=PrtSettings(n_dirs=4096, seed=s))[i] for s in range(4)])
    for T in Ts:  # each randomly rotated direction set
        torch.testing.assert_close(T[[0, 2]], want, rtol=1.5e-2, atol=0)
        assert abs(T[1].item()) < 5e-3 and abs(T[3].item()) < 5e-3  # symmetric about the vertical
    torch.testing.assert_close(Ts.mean(0)[[0, 2]], want, rtol=8e-3, atol=0)
    # The unshadowed value is clearly different: the test sees the shadow.
    assert Ts[:, 0].max() < 0.8 * Y0 * math.pi


def test_deterministic_for_a_seed():
    v, f, n, _ = plane_under_sphere()
    a = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=128, seed=3))
    b = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=128, seed=3))
    c = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=128, seed=4))
    assert torch.equal(a, b)
    assert not torch.equal(a, c)
    assert (a - c).abs().max() < 0.15  # two estimates of the same integral
    plain, w = transport_directions(128, seed=None)
    torch.testing.assert_close(plain, fibonacci_sphere(128)[0])
    assert w.sum().item() == pytest.approx(4 * math.pi)


@pytest.mark.parametrize("lmax", [0, 1, 3])
def test_other_orders(lmax):
    v, f, n = sphere(1)
    T = vertex_transport(v, f, n, lmax=lmax, prt=PrtSettings(n_dirs=1024))
    assert T.shape == (len(v), (lmax + 1) ** 2)
    assert (T - closed_form(n, lmax)).abs().max() <= 2e-3


def test_numpy_inputs_are_accepted():
    v, f, n = sphere(1)
    T = vertex_transport(v.numpy(), f.numpy(), n.numpy(), prt=PrtSettings(n_dirs=64))
    torch.testing.assert_close(T, vertex_transport(v, f, n, prt=PrtSettings(n_dirs=64)))


def test_bad_inputs_raise():
    v, f, n = sphere(1)
    with pytest.raises(InputError, match="bounces"):
        vertex_transport(v, f, n, prt=PrtSettings(bounces=-1))
    with pytest.raises(InputError, match="occlusion"):
        vertex_transport(v, f, n, prt=PrtSettings(bounces=1, occlusion=False))
    with pytest.raises(ValueError, match="lmax"):
        vertex_transport(v, f, n, lmax=-1)
    with pytest.raises(InputError, match="n_dirs"):
        vertex_transport(v, f, n, prt=PrtSettings(n_dirs=0))
    with pytest.raises(InputError, match="empty"):
        vertex_transport(v[:0], f[:0], n[:0])
    with pytest.raises(InputError, match="indices"):
        vertex_transport(v, f + len(v), n)
    with pytest.raises(ShapeError, match="normals"):
        vertex_transport(v, f, n[:, :2])
    with pytest.raises(InputError, match="unit"):
        vertex_transport(v, f, n * 0.5)
    with pytest.raises(InputError, match="albedo"):
        vertex_transport(v, f, n, prt=PrtSettings(bounces=1), albedo=1.5)
    with pytest.raises(ShapeError, match="albedo"):
        vertex_transport(v, f, n, prt=PrtSettings(bounces=1), albedo=torch.ones(len(v), 2))


def test_vertex_subset_gives_the_same_rows_and_zero_elsewhere():
    v, f, n, n_sphere = plane_under_sphere()
    full = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=64, seed=3))
    idx = torch.tensor([n_sphere, 0, 5, n_sphere + 2, 17])
    sub = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=64, seed=3), vertices=idx)
    torch.testing.assert_close(sub[idx], full[idx], rtol=0, atol=1e-6)  # same rays; BLAS blocking differs
    rest = torch.ones(len(v), dtype=torch.bool)
    rest[idx] = False
    assert (sub[rest] == 0).all() and (full[rest] != 0).any()
    none = torch.tensor([], dtype=torch.int64)
    assert (vertex_transport(v, f, n, prt=PrtSettings(n_dirs=16), vertices=none) == 0).all()
    with pytest.raises(InputError, match="bounces"):
        vertex_transport(v, f, n, prt=PrtSettings(n_dirs=16, bounces=1), vertices=idx)
    with pytest.raises(InputError, match="indices"):
        vertex_transport(v, f, n, prt=PrtSettings(n_dirs=16), vertices=torch.tensor([len(v)]))


def test_manifold_option_passes_to_the_mesh_check():
    """A caller that renders one topology in many poses checks it once and then passes "ignore"."""
    import warnings

    from relightnet.prt.mesh_checks import MeshWarning

    v, f, n = sphere(1)
    f3 = torch.cat([f, f[:1]])  # a duplicated face: three faces on its edges
    with pytest.warns(MeshWarning, match="non-manifold"):
        warned = vertex_transport(v, f3, n, prt=PrtSettings(n_dirs=32))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        quiet = vertex_transport(v, f3, n, prt=PrtSettings(n_dirs=32), manifold="ignore")
    torch.testing.assert_close(quiet, warned, rtol=0, atol=0)
    with pytest.raises(InputError, match="non-manifold"):
        vertex_transport(v, f3, n, prt=PrtSettings(n_dirs=32), manifold="error")


def test_cast_lit_writes_into_a_given_array():
    import numpy as np

    from relightnet.prt import make_engine
    from relightnet.prt.transport import cast_lit
    from relightnet.prt.visibility import vertex_rays

    v, f, n, _ = plane_under_sphere()
    dirs, _ = fibonacci_sphere(32)
    rays = vertex_rays(v, n, dirs)
    eng = make_engine(v, f)
    lit, hits = cast_lit(eng, rays, False)
    assert hits is None and lit.shape == (len(v), 32) and (lit[rays.vertex, rays.direction] >= 0).all()
    out = np.full((len(v), 32), 7.0, dtype=np.float32)
    got, hits = cast_lit(eng, rays, True, out=out)
    assert got is out and hits.prim.shape == rays.vertex.shape
    ray = np.zeros((len(v), 32), dtype=bool)
    ray[rays.vertex, rays.direction] = True
    assert np.array_equal(out[ray], lit[ray]) and (out[~ray] == 7).all()
    with pytest.raises(InputError, match="out"):
        cast_lit(eng, rays, False, out=np.zeros((len(v), 31), dtype=np.float32))
