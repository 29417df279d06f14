import math

import numpy as np
import pytest
import torch
import trimesh

from relightnet.checks import InputError, ShapeError
from relightnet.prt import PrtSettings, interreflect, make_engine, transport_directions, vertex_transport
from relightnet.prt.interreflection import BounceOperator, bounce_operator, check_albedo
from relightnet.prt.visibility import vertex_rays
from relightnet.sh import light_to_world, sh_basis

Y0 = 0.5 / math.sqrt(math.pi)


def grid(n=21, size=4.0, y=0.0, up=True):
    """An n×n vertex grid in the plane y, wound to face +y (or −y)."""
    t = torch.linspace(-size / 2, size / 2, n)
    x, z = torch.meshgrid(t, t, indexing="ij")
    v = torch.stack([x, torch.full_like(x, y), z], -1).reshape(-1, 3)
    i = torch.arange(n * n).reshape(n, n)
    a, b, c, d = i[:-1, :-1], i[1:, :-1], i[:-1, 1:], i[1:, 1:]
    f = torch.cat([torch.stack([a, c, b], -1).reshape(-1, 3), torch.stack([b, c, d], -1).reshape(-1, 3)])
    if not up:
        f = f[:, [0, 2, 1]]
    n_ = torch.tensor([0.0, 1.0 if up else -1.0, 0.0]).expand_as(v).contiguous()
    return v, f, n_


def sphere(sub=3, r=0.5, center=(0.0, 0.8, 0.0)):
    m = trimesh.creation.icosphere(subdivisions=sub, radius=r)
    v = torch.tensor(m.vertices, dtype=torch.float32)
    return v + torch.tensor(center), torch.tensor(m.faces), torch.nn.functional.normalize(v, dim=-1)


def merge(*meshes):
    vs, fs, ns, off = [], [], [], 0
    for v, f, n in meshes:
        vs.append(v)
        fs.append(f + off)
        ns.append(n)
        off += len(v)
    return torch.cat(vs), torch.cat(fs), torch.cat(ns)


def cavity():
    """An open-topped box seen from inside: walls and floor face inward (a concave mesh)."""
    m = trimesh.creation.box(extents=(2.0, 2.0, 2.0))
    for _ in range(3):
        m = m.subdivide()
    keep = m.triangles_center[:, 1] < 0.999
    m = trimesh.Trimesh(m.vertices, m.faces[keep], process=True)
    m.invert()
    return (torch.tensor(m.vertices, dtype=torch.float32), torch.tensor(m.faces),
            torch.tensor(m.vertex_normals, dtype=torch.float32))


def test_white_furnace_conserves_energy():
    # Under uniform light, white Lambertian surfaces receive E = π everywhere: T_0 → π·Y0.
    v, f, n = merge(grid(), sphere())
    direct = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=1024, bounces=0))
    full = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=1024, bounces=12), albedo=1.0)
    target = math.pi * Y0
    assert direct[:, 0].min() < 0.7 * target  # strong shadows without bounces
    assert (full[:, 0] / target - 1).abs().max() < 5e-3


def test_bounces_add_energy_and_converge():
    v, f, n = cavity()
    Ts = [vertex_transport(v, f, n, prt=PrtSettings(n_dirs=256, bounces=b), albedo=0.7) for b in range(4)]
    for a, b in zip(Ts[:-1], Ts[1:], strict=True):
        assert (b[:, 0] >= a[:, 0] - 1e-7).all()  # DC never loses energy
    floor = v[:, 1] < -0.99
    assert (Ts[1][floor, 0] > Ts[0][floor, 0] + 1e-3).all()
    steps = [(b - a).norm().item() for a, b in zip(Ts[:-1], Ts[1:], strict=True)]
    assert steps[0] > steps[1] > steps[2] > 0
    assert steps[2] < 0.7 * steps[1]


def test_albedo_zero_means_no_bounce():
    v, f, n = cavity()
    torch.testing.assert_close(
        vertex_transport(v, f, n, prt=PrtSettings(n_dirs=64, bounces=3), albedo=0.0),
        vertex_transport(v, f, n, prt=PrtSettings(n_dirs=64)),
    )


def test_rgb_albedo_colours_each_channel():
    v, f, n = cavity()
    rgb = torch.tensor([0.9, 0.5, 0.1]).expand(len(v), 3)
    T = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=128, bounces=2), albedo=rgb)
    assert T.shape == (len(v), 9, 3) and T.dtype == torch.float32
    for c in range(3):
        grey = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=128, bounces=2), albedo=float(rgb[0, c]))
        torch.testing.assert_close(T[..., c], grey, atol=1e-6, rtol=1e-5)
    per_vertex_grey = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=128, bounces=2),
                                       albedo=torch.full((len(v),), 0.5))
    torch.testing.assert_close(per_vertex_grey, T[..., 1], atol=1e-6, rtol=1e-5)


def test_back_faces_block_but_do_not_reflect():
    receiver = grid(3, 0.2, 0.0, up=True)
    for up in (True, False):
        v, f, n = merge(receiver, grid(9, 4.0, 1.0, up=up))
        direct = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=256))
        bounced = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=256, bounces=2), albedo=1.0)
        assert direct[:9, 0].max() < 0.2 * math.pi * Y0  # the sheet shades the receiver
        if up:  # the receiver sees the sheet's underside (its back): nothing comes back
            torch.testing.assert_close(bounced[:9], direct[:9], atol=0, rtol=0)
        else:  # the sheet faces the receiver, and it is lit from below by the open sky
            assert (bounced[:9, 0] > direct[:9, 0] + 0.05).all()


def test_operator_is_built_once_and_reused():
    v, f, n = cavity()
    dirs_l, w = transport_directions(128, seed=0)
    dirs_w = light_to_world(dirs_l)
    rays = vertex_rays(v, n, dirs_w)
    hits = make_engine(v, f).intersect(rays.origins, rays.dirs)
    op = bounce_operator(rays, hits, f, w, v)
    assert isinstance(op, BounceOperator) and op.matrix.shape == (len(v), len(v))
    assert op.n_rays == len(rays.vertex) and 0 < op.n_front <= op.n_blocked < op.n_rays
    lit = np.zeros((len(v), 128), np.float32)
    lit[rays.vertex, rays.direction] = np.where(hits.prim >= 0, 0, rays.cosine)
    T0 = torch.from_numpy(lit) @ (sh_basis(dirs_l, 2) * w[:, None])
    for albedo in (0.3, 0.8):
        mine = interreflect(T0, op, check_albedo(albedo, len(v)), 2)
        torch.testing.assert_close(mine, vertex_transport(v, f, n, prt=PrtSettings(n_dirs=128, bounces=2),
                                                          albedo=albedo))
    torch.testing.assert_close(interreflect(T0, op, check_albedo(0.5, len(v)), 0), T0)


def test_bad_albedo_and_bounces():
    with pytest.raises(InputError, match="albedo"):
        check_albedo(-0.1, 4)
    with pytest.raises(InputError, match="NaN"):
        check_albedo(torch.tensor([0.5, float("nan"), 0.5, 0.5]), 4)
    with pytest.raises(ShapeError, match="albedo"):
        check_albedo(torch.ones(5), 4)
    assert check_albedo(0.5, 4).shape == (4, 1) and check_albedo(torch.ones(4, 3), 4).shape == (4, 3)
    v, f, n = cavity()
    dirs_l, w = transport_directions(16)
    rays = vertex_rays(v, n, light_to_world(dirs_l))
    op = bounce_operator(rays, make_engine(v, f).intersect(rays.origins, rays.dirs), f, w, v)
    with pytest.raises(InputError, match="bounces"):
        interreflect(torch.zeros(len(v), 9), op, check_albedo(0.5, len(v)), -1)
    with pytest.raises(ShapeError, match="T0"):
        interreflect(torch.zeros(len(v), 9, 3), op, check_albedo(0.5, len(v)), 1)


def test_interreflect_on_device_matches_cpu(device, dtype):
    # The ray casting runs on the CPU (Embree); the bounces are a sparse matmul that runs where the tensors are.
    v, f, n = cavity()
    dirs_l, w = transport_directions(64, seed=0)
    rays = vertex_rays(v, n, light_to_world(dirs_l))
    hits = make_engine(v, f).intersect(rays.origins, rays.dirs)
    op = bounce_operator(rays, hits, f, w, v)
    lit = np.zeros((len(v), 64), np.float32)
    lit[rays.vertex, rays.direction] = np.where(hits.prim >= 0, 0, rays.cosine)
    T0 = (torch.from_numpy(lit).double() @ (sh_basis(dirs_l.double(), 2) * w.double()[:, None])).to(dtype)
    albedo = check_albedo(torch.tensor([0.8, 0.5, 0.3]).expand(len(v), 3), len(v)).to(dtype)
    ref = interreflect(T0, BounceOperator(op.matrix.to(dtype), *(op.n_rays, op.n_blocked, op.n_front)), albedo, 2)
    op_dev = BounceOperator(op.matrix.to(device=device, dtype=dtype), op.n_rays, op.n_blocked, op.n_front)
    out = interreflect(T0.to(device), op_dev, albedo.to(device), 2)
    assert out.device.type == device.type and out.dtype == dtype and out.shape == (len(v), 9, 3)
    assert (out[:, 0] > T0.to(device)[:, 0, None] - 1e-6).all()  # bounces add light
    tol = 1e-5 if dtype == torch.float32 else 1e-10
    torch.testing.assert_close(out.cpu(), ref, atol=tol, rtol=tol)
