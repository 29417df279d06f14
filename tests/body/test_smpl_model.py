import pickle

import numpy as np
import pytest
import torch

from relightnet.body import SMPLBody
from relightnet.body.smpl_model import SMPL_JOINT_NAMES, load_smpl_file, smpl_to_world, spherical_uv
from relightnet.checks import InputError, ShapeError


@pytest.fixture(scope="module")
def smpl(smpl_file):
    return SMPLBody(smpl_file, ground="none")


def test_shapes_b1_b2(smpl, smpl_file):
    o1 = smpl()
    o2 = smpl(pose=0.2 * torch.randn(2, 24, 3), betas=torch.randn(2, 10), trans=torch.zeros(3))
    for o, b in ((o1, 1), (o2, 2)):
        assert o.verts.shape == (b, 6890, 3) and o.verts.dtype == torch.float32
        assert o.normals.shape == (b, 6890, 3) and o.joints.shape == (b, 24, 3)
        assert o.faces.dtype == torch.int64 and o.faces.shape[1] == 3 and o.uv_faces.shape == o.faces.shape
        assert torch.allclose(o.normals.norm(dim=-1), torch.ones(b, 6890), atol=1e-4)
    assert o1.joint_names == SMPL_JOINT_NAMES


def test_zero_pose_is_template_and_frame_is_identity(smpl, smpl_file):
    data = np.load(smpl_file)
    o = smpl()
    v = torch.as_tensor(data["v_template"], dtype=torch.float32)
    assert torch.allclose(o.verts[0], v, atol=1e-5)
    assert torch.allclose(o.joints[0], torch.as_tensor(data["J_regressor"] @ data["v_template"]).float(), atol=1e-5)
    x = torch.randn(4, 3)
    assert torch.equal(smpl_to_world(x), x)
    # Area-weighted vertex normals of the ellipsoid follow its analytic normal (x/a², y/b², z/c²).
    p = v - torch.tensor([0.0, -0.1, 0.0])
    exact = torch.nn.functional.normalize(p / torch.tensor([0.25, 0.85, 0.15]) ** 2, dim=-1)
    cos = (o.normals[0] * exact).sum(-1)
    assert cos.min() > 0.9 and cos.mean() > 0.995


def test_pose_betas_trans_act(smpl):
    rest = smpl().verts
    pose = torch.zeros(24, 3)
    pose[1, 0] = 0.5  # left hip
    bent = smpl(pose=pose).verts
    assert (bent - rest).norm(dim=-1).max() > 0.01
    fat = smpl(betas=torch.ones(10)).verts
    assert (fat - rest).norm(dim=-1).max() > 0.01
    t = torch.tensor([1.0, 2.0, 3.0])
    assert torch.allclose(smpl(trans=t).verts, rest + t, atol=1e-5)
    flat = smpl(pose=0.1 * torch.ones(2, 72)).verts
    assert torch.allclose(flat, smpl(pose=0.1 * torch.ones(2, 24, 3)).verts)
    with pytest.raises(ShapeError, match="betas: expected at most 10"):
        smpl(betas=torch.zeros(11))
    with pytest.raises(InputError, match="unknown parameter"):
        smpl(phenotype={"age": 0.5})


def test_ground_rest(smpl_file):
    m = SMPLBody(smpl_file)
    o = m(betas=torch.tensor([[0.0] * 10, [3.0] * 10]))
    assert o.verts[:, :, 1].amin(1).abs().max() < 1e-5


def test_fallback_and_given_uvs(smpl, tmp_path, smpl_arrays):
    assert smpl.uv.shape == (6890, 2) and smpl.uv.min() >= 0 and smpl.uv.max() <= 1
    assert torch.equal(smpl.uv_faces, smpl.faces)
    assert torch.allclose(spherical_uv(torch.tensor([[0.0, 0, 1], [0, 0, -1], [0, 1, 0], [0, -1, 0]]))[0],
                          torch.tensor([0.5, 0.5]))
    arrs = smpl_arrays()
    arrs["vt"] = np.random.default_rng(0).uniform(size=(7000, 2))
    arrs["ft"] = np.random.default_rng(1).integers(0, 7000, size=arrs["f"].shape)
    path = tmp_path / "with_uv.npz"
    np.savez(path, **arrs)
    m = SMPLBody(path)
    assert m.uv.shape == (7000, 2) and torch.equal(m.uv_faces, torch.as_tensor(arrs["ft"]))


def test_pkl_without_chumpy_loads_like_npz(smpl, tmp_path, smpl_arrays):
    import scipy.sparse

    arrs = smpl_arrays()
    arrs["J_regressor"] = scipy.sparse.csc_matrix(arrs["J_regressor"])
    path = tmp_path / "model.pkl"
    with open(path, "wb") as f:
        pickle.dump(arrs, f)
    m = SMPLBody(path, ground="none")
    pose = 0.3 * torch.randn(1, 24, 3, generator=torch.Generator().manual_seed(0))
    assert torch.allclose(m(pose=pose).verts, smpl(pose=pose).verts, atol=1e-5)


def test_file_errors(tmp_path, smpl_arrays):
    arrs = smpl_arrays(n_verts=200)
    for key in ("weights", "kintree_table"):
        bad = {k: v for k, v in arrs.items() if k != key}
        np.savez(tmp_path / "bad.npz", **bad)
        with pytest.raises(InputError, match=f"bad.npz: missing key.*'{key}'"):
            load_smpl_file(tmp_path / "bad.npz")
    bad = dict(arrs, weights=arrs["weights"][:, :23])
    np.savez(tmp_path / "bad.npz", **bad)
    with pytest.raises(ShapeError, match=r"bad.npz: key 'weights': expected \(V=200, J=24\), got \(200, 23\)"):
        load_smpl_file(tmp_path / "bad.npz")
    with pytest.raises(InputError, match="no such"):
        SMPLBody(tmp_path / "missing.npz")
    # Fewer than 6890 vertices still works (smplx's extra keypoint ids are not used).
    np.savez(tmp_path / "small.npz", **arrs)
    assert SMPLBody(tmp_path / "small.npz")().verts.shape == (1, 200, 3)


def test_official_style_pkl_with_chumpy_objects_loads_without_chumpy(tmp_path, smpl_arrays, monkeypatch):
    """Official SMPL .pkl files hold chumpy ``Ch`` objects and a scipy csc J_regressor (protocol 2)."""
    import sys
    import types

    import scipy.sparse

    pkg, mod = types.ModuleType("chumpy"), types.ModuleType("chumpy.ch")

    class Ch:  # pickles under chumpy's own name, as the official files do
        def __init__(self, x):
            self.x, self._dirty_vars, self._itr = np.asarray(x, np.float64), set(), None

    Ch.__module__, Ch.__qualname__ = "chumpy.ch", "Ch"
    mod.Ch, pkg.ch = Ch, mod
    arrs = smpl_arrays(n_verts=200)
    official = dict(arrs, v_template=Ch(arrs["v_template"]), shapedirs=Ch(arrs["shapedirs"]),
                    weights=Ch(arrs["weights"]), J_regressor=scipy.sparse.csc_matrix(arrs["J_regressor"]),
                    bs_style="lbs", bs_type="lrotmin")
    with monkeypatch.context() as m:
        m.setitem(sys.modules, "chumpy", pkg)
        m.setitem(sys.modules, "chumpy.ch", mod)
        (tmp_path / "basicModel.pkl").write_bytes(pickle.dumps(official, protocol=2))
    data = load_smpl_file(tmp_path / "basicModel.pkl")
    assert "chumpy" not in sys.modules
    for k in ("v_template", "shapedirs", "weights", "J_regressor"):
        np.testing.assert_array_equal(data[k], np.asarray(arrs[k], np.float64))
