import math

import pytest
import torch

from relightnet.body import PHENOTYPES, POSE_PRESETS, BodyOutput, pose_preset
from relightnet.body.anny_model import ANNY_TO_WORLD, anny_to_world
from relightnet.body.base import vertex_normals
from relightnet.checks import InputError, ShapeError

N_VERTS, N_FACES, N_BONES, N_UV = 13718, 27420, 104, 21334


def _j(out: BodyOutput, name: str, b: int = 0) -> torch.Tensor:
    return out.joints[b, out.joint_names.index(name)]


def test_shapes_dtypes_b1_b2(anny_body):
    o1 = anny_body()
    pose = torch.zeros(2, N_BONES, 3)
    pose[1, anny_body.joint_index("upperleg01.L"), 0] = -0.5
    o2 = anny_body(pose=pose)
    for o, b in ((o1, 1), (o2, 2)):
        assert o.verts.shape == (b, N_VERTS, 3) and o.verts.dtype == torch.float32
        assert o.normals.shape == (b, N_VERTS, 3) and o.normals.dtype == torch.float32
        assert o.joints.shape == (b, N_BONES, 3)
        assert o.faces.shape == (N_FACES, 3) and o.faces.dtype == torch.int64
        assert o.uv.shape == (N_UV, 2) and o.uv_faces.shape == (N_FACES, 3) and o.uv_faces.dtype == torch.int64
        assert len(o.joint_names) == N_BONES and o.batch_size == b
    assert torch.allclose(o2.verts[0], o1.verts[0], atol=1e-5)
    assert (o2.verts[1] - o1.verts[0]).norm(dim=-1).max() > 0.2
    assert o2[1].verts.shape == (1, N_VERTS, 3)


def test_topology_triangles_uvs_consistent_and_closed(anny_body):
    f, ft, uv = anny_body.faces, anny_body.uv_faces, anny_body.uv
    assert f.min() >= 0 and f.max() == N_VERTS - 1 and ft.min() >= 0 and ft.max() < N_UV
    assert (f[:, 0] != f[:, 1]).all() and (f[:, 1] != f[:, 2]).all() and (f[:, 0] != f[:, 2]).all()
    assert uv.min() >= 0 and uv.max() <= 1
    # Triangulated together: every UV index is used by exactly one vertex.
    pairs = torch.unique(torch.stack([ft.reshape(-1), f.reshape(-1)], 1), dim=0)
    assert len(torch.unique(pairs[:, 0])) == len(pairs)
    # Closed 2-manifold: every undirected edge is shared by exactly two faces.
    e = torch.cat([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]).sort(dim=1).values
    _, counts = torch.unique(e, dim=0, return_counts=True)
    assert (counts == 2).all()


def test_normals_unit_and_outward(anny_body):
    o = anny_body()
    n, v = o.normals[0], o.verts[0]
    assert torch.allclose(n.norm(dim=-1), torch.ones(N_VERTS), atol=1e-4)
    assert ((n * (v - v.mean(0))).sum(-1)).mean() > 0
    # Against the nearest joint, far more robust than the centroid: almost all point away from it.
    d = torch.cdist(v, o.joints[0]).argmin(1)
    assert ((n * (v - o.joints[0, d])).sum(-1) > 0).float().mean() > 0.85
    f = o.faces
    vol = (v[f[:, 0]] * torch.linalg.cross(v[f[:, 1]], v[f[:, 2]], dim=-1)).sum() / 6
    assert 0.03 < vol < 0.15  # positive: counter-clockwise seen from outside; ~70 litres
    assert torch.allclose(vertex_normals(o.verts, o.faces), o.normals, atol=1e-6)


def test_frame_rotation_matrix():
    C = ANNY_TO_WORLD
    assert torch.allclose(C @ C.T, torch.eye(3, dtype=C.dtype)) and torch.det(C) == 1
    up_anny, facing_anny, left_anny = torch.tensor([[0, 0, 1.0], [0, -1.0, 0], [1.0, 0, 0]]).unbind(0)
    assert torch.equal(anny_to_world(up_anny), torch.tensor([0, 1.0, 0]))
    assert torch.equal(anny_to_world(facing_anny), torch.tensor([0, 0, 1.0]))
    assert torch.equal(anny_to_world(left_anny), torch.tensor([1.0, 0, 0]))


def test_head_up_face_toward_plus_z_feet_on_ground(anny_body):
    o = anny_body()
    v = o.verts[0]
    head, pelvis, ankle = _j(o, "head"), _j(o, "root"), _j(o, "foot.L")
    assert head[1] > pelvis[1] + 0.5 > ankle[1] + 0.5
    assert abs(v[:, 1].min()) < 1e-5 and 1.6 < v[:, 1].max() < 1.8
    # The nose is the most forward (+z) vertex of the head, on the midline, ahead of the head joint.
    top = v[:, 1] > _j(o, "neck03")[1]
    nose = v[top][v[top][:, 2].argmax()]
    assert abs(nose[0]) < 0.01 and nose[2] > head[2] + 0.08
    assert _j(o, "eye.L")[2] > head[2] + 0.05
    assert _j(o, "wrist.L")[0] > 0.3 and _j(o, "wrist.R")[0] < -0.3  # the person's left is +x


def test_root_rotation_is_about_world_up(anny_body):
    quarter = anny_body(pose={"root": (0.0, math.pi / 2, 0.0)})
    eye = (_j(quarter, "eye.L") + _j(quarter, "eye.R")) / 2 - _j(quarter, "head")
    assert eye[0] > 0.05 and abs(eye[2]) < 0.02  # facing +z turned 90° about +y faces +x


def test_ground_modes_and_translation(anny_body):
    from relightnet.body import AnnyBody

    phen = {"height": torch.tensor([0.1, 0.9]), "age": torch.tensor([0.3, 0.9])}
    o = anny_body(phenotype=phen)
    assert o.verts.shape[0] == 2 and o.verts[:, :, 1].amin(1).abs().max() < 1e-5
    t = torch.tensor([0.3, -0.2, 1.0])
    ot = anny_body(trans=t)
    assert torch.allclose(ot.verts - anny_body().verts, t.expand(1, N_VERTS, 3), atol=1e-5)
    native = AnnyBody(model=anny_body.anny, ground="none")(pose=anny_body.pose("arms_crossed"))
    assert _j(native, "root").abs().max() < 1e-6
    squat = {"upperleg01.L": (-1.2, 0, 0), "upperleg01.R": (-1.2, 0, 0),
             "lowerleg01.L": (1.6, 0, 0), "lowerleg01.R": (1.6, 0, 0)}
    framed = AnnyBody(model=anny_body.anny, ground="frame")(pose=squat)
    assert abs(framed.verts[0, :, 1].min()) < 1e-5
    assert anny_body(pose=squat).verts[0, :, 1].min() > 0.05  # the rest grounding leaves a squat floating


def test_phenotype_values_and_errors(anny_body):
    short = anny_body(phenotype={"height": 0.1}).verts[0, :, 1].max()
    tall = anny_body(phenotype={"height": 0.9}).verts[0, :, 1].max()
    assert tall > short + 0.3
    defaults = torch.tensor([PHENOTYPES[k][2] for k in PHENOTYPES])
    assert torch.allclose(anny_body(phenotype=defaults).verts, anny_body().verts)
    with pytest.raises(InputError, match="'age'.*-0.333, 1"):
        anny_body(phenotype={"age": 1.5})
    with pytest.raises(InputError, match="unknown name.*'bmi'"):
        anny_body(phenotype={"bmi": 0.5})
    with pytest.raises(ShapeError, match=r"phenotype: expected \(B, 6\)"):
        anny_body(phenotype=torch.full((2, 5), 0.5))


def test_param_errors(anny_body):
    with pytest.raises(InputError, match="unknown parameter"):
        anny_body(betas=torch.zeros(10))
    with pytest.raises(ShapeError, match=r"pose: expected \(B, 104, 3\)"):
        anny_body(pose=torch.zeros(2, 24, 3))
    with pytest.raises(InputError, match="batch"):
        anny_body(pose=torch.zeros(2, N_BONES, 3), trans=torch.zeros(3, 3))
    with pytest.raises(InputError, match="unknown Anny bone 'elbow'"):
        anny_body(pose={"elbow": (0, 0, 1.0)})
    with pytest.raises(InputError, match="NaN"):
        anny_body(trans=torch.tensor([0, float("nan"), 0]))


def test_pose_dict_matches_tensor(anny_body):
    pose = anny_body.pose("arms_down")
    by_name = {n: pose[0, i] for i, n in enumerate(anny_body.joint_names) if pose[0, i].abs().sum() > 0}
    assert set(by_name) == set(pose_preset("arms_down"))
    assert torch.allclose(anny_body(pose=by_name).verts, anny_body(pose=pose).verts, atol=1e-6)


def test_pose_presets(anny_body):
    names = list(POSE_PRESETS)
    assert {"rest", "tpose", "apose", "arms_down", "arms_crossed"} <= set(names)
    out = anny_body(pose=torch.cat([anny_body.pose(n) for n in names]))
    rest = out.verts[names.index("rest")]
    for i, n in enumerate(names):
        if n != "rest":
            assert (out.verts[i] - rest).norm(dim=-1).max() > 0.05, n
    t = names.index("tpose")
    for s in "LR":
        assert abs(_j(out, f"wrist.{s}", t)[1] - _j(out, f"upperarm01.{s}", t)[1]) < 0.05
    down = names.index("arms_down")
    assert abs(_j(out, "wrist.L", down)[0]) < 0.3 and _j(out, "wrist.L", down)[1] < _j(out, "root", down)[1] + 0.05
    c = names.index("arms_crossed")
    chest_z = max(_j(out, b, c)[2].item() for b in ("spine01", "spine02", "spine03"))
    for s in "LR":
        w = _j(out, f"wrist.{s}", c)
        assert w[2] > chest_z + 0.15 and abs(w[0]) < 0.15
        assert _j(out, "root", c)[1] < w[1] < _j(out, "neck01", c)[1]
    assert _j(out, "wrist.L", c)[0] < 0 < _j(out, "wrist.R", c)[0]  # crossed: each hand on the other side
    with pytest.raises(InputError, match="pose preset"):
        pose_preset("dab")
