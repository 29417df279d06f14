import math
import pickle

import numpy as np
import pytest
import torch

from relightnet.body import Motion, SMPLBody, load_motion, save_motion
from relightnet.body.motion_io import Z_UP_TO_Y_UP, reorient_motion
from relightnet.checks import InputError, ShapeError


def _arrays(T=10, seed=0):
    rng = np.random.default_rng(seed)
    return {"poses": 0.2 * rng.standard_normal((T, 72)), "betas": rng.standard_normal(10),
            "trans": rng.standard_normal((T, 3)), "fps": np.float32(25.0)}


def test_round_trip_npz_and_pkl(tmp_path):
    m = Motion(torch.randn(7, 72), torch.randn(10), torch.randn(7, 3), fps=24.0,
               camera={"K": torch.eye(3), "t": torch.zeros(7, 3)})
    for name in ("clip.npz", "clip.pkl"):
        back = load_motion(save_motion(tmp_path / name, m))
        assert torch.allclose(back.poses, m.poses) and torch.allclose(back.betas, m.betas)
        assert torch.allclose(back.trans, m.trans) and back.fps == 24.0 and back.n_frames == 7
        assert set(back.camera) == {"K", "t"} and torch.equal(back.camera["K"], torch.eye(3))
    np.savez(tmp_path / "plain.npz", **{k: v for k, v in _arrays().items() if k != "fps"})
    plain = load_motion(tmp_path / "plain.npz")
    assert plain.fps == 30.0 and plain.camera is None and plain.poses.dtype == torch.float32


def test_amass_style_framerate_key(tmp_path):
    a = _arrays()
    del a["fps"]
    np.savez(tmp_path / "amass.npz", **a, mocap_framerate=np.float64(120.0))
    assert load_motion(tmp_path / "amass.npz").fps == 120.0


@pytest.mark.parametrize(
    "key, value, message",
    [
        ("poses", np.zeros((10, 69)), "motion.npz: key 'poses': expected (T, 72), got (10, 69)"),
        ("poses", np.zeros(72), "motion.npz: key 'poses': expected (T, 72), got (72,)"),
        ("betas", np.zeros(16), "motion.npz: key 'betas': expected (10,), got (16,)"),
        ("trans", np.zeros((9, 3)), "motion.npz: key 'trans': expected (T=10, 3), got (9, 3)"),
        ("trans", np.zeros((10, 2)), "motion.npz: key 'trans': expected (T=10, 3), got (10, 2)"),
        ("fps", np.zeros(2), "motion.npz: key 'fps': expected a scalar, got (2,)"),
    ],
)
def test_bad_shapes_name_the_key_and_file(tmp_path, key, value, message):
    a = dict(_arrays(), **{key: value})
    np.savez(tmp_path / "motion.npz", **a)
    with pytest.raises(ShapeError) as e:
        load_motion(tmp_path / "motion.npz")
    assert str(e.value) == message


@pytest.mark.parametrize("key", ["poses", "betas", "trans"])
def test_missing_keys(tmp_path, key):
    a = {k: v for k, v in _arrays().items() if k != key}
    with open(tmp_path / "walk.pkl", "wb") as f:
        pickle.dump(a, f)
    with pytest.raises(InputError, match=f"walk.pkl: missing key '{key}'"):
        load_motion(tmp_path / "walk.pkl")


def test_bad_values_and_files(tmp_path):
    a = _arrays()
    a["trans"][3, 1] = np.nan
    np.savez(tmp_path / "m.npz", **a)
    with pytest.raises(InputError, match="m.npz: key 'trans': contains NaN"):
        load_motion(tmp_path / "m.npz")
    np.savez(tmp_path / "m.npz", **dict(_arrays(), fps=np.float32(-5)))
    with pytest.raises(InputError, match="m.npz: key 'fps': expected a positive number"):
        load_motion(tmp_path / "m.npz")
    with pytest.raises(InputError, match="no such motion file"):
        load_motion(tmp_path / "none.npz")
    (tmp_path / "m.txt").write_text("poses")
    with pytest.raises(InputError, match=r"m.txt: expected a .npz or .pkl"):
        load_motion(tmp_path / "m.txt")
    (tmp_path / "junk.pkl").write_bytes(b"not a pickle")
    with pytest.raises(InputError, match="junk.pkl: not a readable motion file"):
        load_motion(tmp_path / "junk.pkl")


def test_motion_drives_smpl_body(tmp_path, smpl_file):
    np.savez(tmp_path / "clip.npz", **_arrays(T=6))
    m = load_motion(tmp_path / "clip.npz")
    body = SMPLBody(smpl_file, ground="none")
    out = body(m.body_params())
    assert out.verts.shape == (6, 6890, 3) and out.joints.shape == (6, 24, 3)
    still = body(pose=m.poses[:1].reshape(1, 24, 3), betas=m.betas, trans=m.trans[:1])
    assert torch.allclose(out.verts[:1], still.verts, atol=1e-5)


def test_reorient_motion_rotates_the_posed_bodies(tmp_path, smpl_file):
    np.savez(tmp_path / "clip.npz", **_arrays(T=4, seed=3))
    m = load_motion(tmp_path / "clip.npz")
    body = SMPLBody(smpl_file, ground="none")
    root = body(betas=m.betas).joints[0, 0]
    y_up = reorient_motion(m, Z_UP_TO_Y_UP, root)
    a, b = body(m.body_params()).verts, body(y_up.body_params()).verts
    assert torch.allclose(b, a @ Z_UP_TO_Y_UP.T, atol=1e-4)
    R = torch.tensor([[math.cos(1.0), 0, math.sin(1.0)], [0, 1.0, 0], [-math.sin(1.0), 0, math.cos(1.0)]])
    assert torch.allclose(body(reorient_motion(m, R, root).body_params()).verts, a @ R.T, atol=1e-4)
