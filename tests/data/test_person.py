"""The person stage: the clothed mesh, its PRT once per group, turned into each sample's camera frame."""

import math

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.data.clothed import clothed_mesh, hidden_body_share
from relightnet.data.config import SynthConfig, sample_seed
from relightnet.data.garments import garment_probs, sample_garments
from relightnet.data.generate import generate_sample, generate_samples, generate_sequence, prepare_assets
from relightnet.data.person import (
    group_seed,
    person_stage,
    person_transport,
    seen_vertices,
    transport_to_camera,
    vertex_colors,
)
from relightnet.data.render_sample import CLIP_KEY, _seen, _streams, _view_stage, clip_geometry, render_clip
from relightnet.data.textures import paint_albedo, sample_outfit
from relightnet.prt import PrtSettings, vertex_transport
from relightnet.raster import Fragments, perspective_camera
from relightnet.render import light_in_world
from relightnet.sh import sh_basis
from relightnet.sh.irradiance import cosine_lobe_per_coeff

pytestmark = pytest.mark.usefixtures("one_thread")  # tests/data/conftest.py

ALL = {"upper": {"open_coat": 1}, "lower": {"skirt": 1}, "head": {"hat": 1}, "hair": {"long": 1}}
CFG = SynthConfig(res=48, n_dirs=16, partial_crop_prob=0.0, garment_probs=ALL)


@pytest.fixture(scope="module")
def assets(anny_body):
    return prepare_assets(anny_body, texture_size=64)


def _rotation(yaw: float, pitch: float) -> torch.Tensor:
    cy, sy, cp, sp = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch)
    Ry = torch.tensor([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]], dtype=torch.float64)
    Rx = torch.tensor([[1, 0, 0], [0, cp, -sp], [0, sp, cp]], dtype=torch.float64)
    return Rx @ Ry


def test_transport_turns_with_the_view(assets):
    body = assets.body
    with torch.no_grad():
        out = body(pose=body.pose("arms_down"))
    v, n, f = out.verts[0], out.normals[0], body.faces
    Q = _rotation(0.7, 0.2)
    Tw = vertex_transport(v, f, n, prt=PrtSettings(n_dirs=64, seed=3), manifold="ignore")
    Tc = transport_to_camera(Tw, Q, 2)
    # Shading is the same whether the light is taken in the camera's frame or the world's.
    L = torch.randn(9, 3, generator=torch.Generator().manual_seed(0))
    cam = perspective_camera(torch.cat([torch.cat([Q.float(), torch.zeros(3, 1)], 1),
                                        torch.tensor([[0.0, 0, 0, 1]])])[None], (8, 8), fov_deg=40)
    Lw = light_in_world(L, cam)[0]
    torch.testing.assert_close(Tc @ L, Tw @ Lw, atol=2e-5, rtol=1e-5)
    # Unoccluded, it is the closed form at the camera-frame normals (quadrature error of 1024 directions).
    Tu = transport_to_camera(vertex_transport(v, f, n, prt=PrtSettings(occlusion=False, n_dirs=1024, seed=3)), Q, 2)
    n_cam = n.double() @ Q.T
    from relightnet.sh import world_to_light

    closed = sh_basis(world_to_light(n_cam), 2) * cosine_lobe_per_coeff(2, dtype=torch.float64)
    assert float((Tu.double() - closed).abs().max()) < 0.02
    with pytest.raises(Exception, match="coefficients"):
        transport_to_camera(Tw[:, :4], Q, 2)


def test_a_group_shares_its_person_and_equals_single_samples(assets):
    both = generate_samples(CFG, "train", [4, 5, 6], assets)
    for i, s in zip((4, 5, 6), both, strict=True):
        one = generate_sample(CFG, "train", i, assets)
        assert one.meta == s.meta and all(one.arrays[k].tobytes() == v.tobytes() for k, v in s.arrays.items())
    for s in both:  # exact ground truth of the clothed person: image = albedo ⊙ (T · L) within 1e-6 of its range
        x, m = s.arrays, s.arrays["mask"] > 0
        shading = np.einsum("hwk,kc->hwc", x["transport"].astype(np.float64), x["light"].astype(np.float64))
        assert np.abs(x["image"] - x["albedo"] * shading)[m].max() <= 1e-6 * x["image"][m].max()
        assert (s.arrays["parts"][m] > 0).all() and len(s.meta["garments"]["types"]) >= 3
    a, b = both[0].meta, both[1].meta
    assert a["prt"]["reuse"] == {"group": 1, "member": 0, "size": 4} and b["prt"]["reuse"]["member"] == 1
    assert a["phenotype"] == b["phenotype"] and a["garments"]["types"] == b["garments"]["types"]
    assert a["pose"]["yaw_deg"] != b["pose"]["yaw_deg"] and a["light"] != b["light"]
    assert not np.array_equal(both[0].arrays["transport"], both[1].arrays["transport"])
    with pytest.raises(Exception, match="ascending"):
        generate_samples(CFG, "train", [5, 4], assets)


def test_clothed_mesh_tables(assets):
    rng = np.random.default_rng(0)
    outfit = sample_outfit(rng)
    outfit["hair"] = outfit["hair"] or [0.1, 0.06, 0.03]  # not bald: long hair too
    g = sample_garments(rng, garment_probs(ALL), outfit)
    body = assets.body
    with torch.no_grad():
        out = body(pose=body.pose("apose"))
    field = assets.region_field(outfit["sleeves"], outfit["legs"], "short")
    tex = paint_albedo(assets.atlas, field, outfit)
    m = clothed_mesh(g, outfit, out.verts, out.normals, out.joints, body, assets.garment_tables(), tex, field,
                     assets.atlas)
    V, F, S = body.num_verts, body.faces.shape[0], tex.shape[0]
    assert m.n_body_faces == F and m.faces.shape == m.uv_faces.shape and int(m.faces.max()) < m.verts.shape[1]
    assert int(m.uv_faces.max()) < len(m.uv) and float(m.uv.min()) >= 0 and float(m.uv.max()) <= 1
    assert m.tex.shape == (S, 3 * S, 3)  # body, the coat's outer panel, the rings panel
    assert float(m.tex.min()) >= 0.02 - 1e-6 and float(m.tex.max()) <= 0.9 + 1e-6
    assert m.field.shape == (m.verts.shape[1], 5) and np.allclose(m.field.sum(1), 1, atol=1e-5)
    assert not m.covered[F:].any() and m.covered[:F].any() and not m.hidden[V:].any() and m.hidden[:V].any()
    assert set(m.types) == {"open_coat", "skirt", "hat", "long_hair"}
    # The garments' outer sides are subdivided once: the last M vertices are their edges' midpoints.
    mid, nv = m.midpoints, m.verts.shape[1]
    assert mid.shape[1] == 3 and torch.equal(mid[:, 0], torch.arange(nv - len(mid), nv)) and len(mid) > 1000
    assert (mid[:, 1:] >= V).all() and (mid[:, 1:] < nv - len(mid)).all()
    torch.testing.assert_close(m.verts[:, mid[:, 0]], 0.5 * (m.verts[:, mid[:, 1]] + m.verts[:, mid[:, 2]]))
    # Body vertices keep their painted albedo; the texture lookup is what the renderer samples.
    c = vertex_colors(m)
    assert c.shape == (m.verts.shape[1], 3) and float(c.min()) >= 0.02 - 1e-6
    # The body-through-cloth share counts covered faces against garment faces.
    cov = torch.nonzero(m.covered).flatten()[:3]
    pix = torch.cat([cov, torch.tensor([F, F + 1, F + 2, F + 3, F + 4, F + 5]), torch.tensor([0])])
    expect = 3 / 9 if not m.covered[0] else 4 / 10
    assert hidden_body_share(pix, m.covered, F) == pytest.approx(expect)
    assert hidden_body_share(torch.tensor([0, 1]), torch.zeros(F + 10, dtype=torch.bool), F) == 0.0


def test_person_transport_skips_only_hidden_vertices(assets):
    p = person_transport(CFG, person_stage(CFG, _streams(group_seed(CFG, "train", 0)[0]), assets, 1))
    T, hidden = p.transport[0], p.mesh.hidden
    assert T.shape == (p.mesh.verts.shape[1], 9) and p.transport_unoccluded.shape[1:] == T.shape
    assert hidden.any() and not hidden[assets.body.num_verts:].any()
    assert (T[hidden] == 0).all()
    # Cloth is lit: its outer sides (the first half of each two-sided piece) mostly see the sky.
    cloth = T[assets.body.num_verts:, 0]
    assert (cloth > 0).float().mean() > 0.5 and float(cloth.max()) > 0.5
    assert (T[:, 0] <= p.transport_unoccluded[0, :, 0] + 1e-5).all()


@pytest.mark.slow
def test_casting_only_the_seen_vertices_changes_no_array(assets):
    # The PRT of a group casts the vertices its views show; a vertex's row is that of the full
    # computation bit for bit, so every array equals the one rendered from the full PRT.
    person = person_stage(CFG, _streams(group_seed(CFG, "train", 8)[0]), assets, 1)
    full = person_transport(CFG, person)
    views = [_view_stage(CFG, person, sample_seed(CFG, "train", i)) for i in (8, 9)]
    seen = _seen(person, views)
    part = person_transport(CFG, person, seen)
    V = person.mesh.verts.shape[1]
    assert seen.shape == (1, V) and 0 < int(seen.sum()) < V
    rows = seen[0] & ~person.mesh.hidden
    assert torch.equal(part.transport[0, rows], full.transport[0, rows]) and (part.transport[0, ~rows] == 0).all()
    assert torch.equal(part.transport_unoccluded, full.transport_unoccluded)
    for i in (8, 9):  # the samples made with the full PRT are the generated ones
        ref = render_clip(CFG, "train", i, sample_seed(CFG, "train", i), assets, None, full)
        one = generate_sample(CFG, "train", i, assets)
        assert ref.meta == one.meta and all(ref.arrays[k].tobytes() == v.tobytes() for k, v in one.arrays.items())
    with pytest.raises(InputError, match="seen"):
        person_transport(CFG, person, seen[:, :10])
    # A clip casts, frame by frame, the vertices that frame shows: the same arrays as from the full PRT.
    cfg, ss = CFG.replace(res=32), np.random.SeedSequence(sample_seed(CFG, "train", 3).entropy, spawn_key=(CLIP_KEY,))
    clip_person = person_transport(cfg, person_stage(cfg, _streams(ss), assets, 2))
    ref = render_clip(cfg, "train", 3, ss, assets, 2, clip_person)
    one = generate_sequence(cfg, "train", 3, 2, assets)
    assert ref.meta == one.meta and all(ref.arrays[k].tobytes() == v.tobytes() for k, v in one.arrays.items())
    f = person.mesh.faces
    views = [Fragments(torch.tensor(pix), torch.tensor(pix_face), torch.full((len(pix), 3), 1 / 3),
                       torch.zeros(len(pix)), (1, 2, 2)) for pix, pix_face in (([0, 1], [0, 3]), ([2], [3]))]
    assert torch.equal(seen_vertices(f, V, views).nonzero().flatten(), f[[0, 3]].flatten().unique())


@pytest.mark.slow
def test_clothed_clips_move_with_the_body(assets):
    cfg = CFG.replace(res=32, n_dirs=8)
    geo = clip_geometry(cfg, "train", 2, 12, assets)
    V = assets.body.num_verts
    assert geo.verts.shape[1] > V and {"open_coat", "skirt", "hat"} <= set(geo.garments["types"])
    step_body = (geo.verts[11, :V] - geo.verts[0, :V]).norm(dim=1)
    step_cloth = (geo.verts[11, V:] - geo.verts[0, V:]).norm(dim=1)
    assert float(step_body.max()) > 0.01 and float(step_cloth.max()) > 0.01
    clip = generate_sequence(cfg, "train", 2, 3, assets)  # the same clip's first frames
    a = clip.arrays
    shading = np.einsum("thwk,tkc->thwc", a["transport"].astype(np.float64), a["light"].astype(np.float64))
    m = a["mask"] > 0
    assert np.abs(a["image"] - a["albedo"] * shading)[m].max() <= 1e-6 * a["image"][m].max()
    assert len(clip.meta["garments"]["hidden_body_share"]) == 3
