import numpy as np
import pytest
import torch

from relightnet.body import AnnyMotion, load_anny_motion, save_anny_motion
from relightnet.body.anny_motion import is_anny_motion
from relightnet.checks import InputError, ShapeError


def _motion(T=3, J=104, names=None):
    names = names or tuple(f"b{i}" for i in range(J))
    return AnnyMotion(0.1 * torch.ones(T, J, 3), torch.zeros(T, 3), torch.tensor([0.5, 0.78, 0.5, 0.5, 0.37, 0.5]),
                      names, 25.0, {"camera_intrinsics": torch.tensor([100.0, 100.0, 32.0, 24.0]),
                                    "interpolated": torch.tensor([0.0, 1.0, 0.0])})


def test_round_trip(tmp_path):
    m = _motion()
    save_anny_motion(tmp_path / "m.npz", m)
    assert is_anny_motion(tmp_path / "m.npz")
    back = load_anny_motion(tmp_path / "m.npz", m.bone_names)
    assert torch.equal(back.pose, m.pose) and back.fps == 25.0 and back.bone_names == m.bone_names
    assert torch.equal(back.extra["interpolated"], m.extra["interpolated"])
    p = back.body_params()
    assert p["pose"].shape == (3, 104, 3) and p["phenotype"].shape == (1, 6)


def _write(path, **arrays):
    base = {"body_model": np.array("anny"), "pose": np.zeros((2, 4, 3), np.float32),
            "bone_names": np.array(["a", "b", "c", "d"]), "trans": np.zeros((2, 3), np.float32),
            "phenotype": np.array([0.5, 0.78, 0.5, 0.5, 0.37, 0.5], np.float32)}
    base.update(arrays)
    np.savez(path, **{k: v for k, v in base.items() if v is not None})
    return path


@pytest.mark.parametrize("change, error, text", [
    ({"body_model": np.array("smpl")}, InputError, "key 'body_model': expected 'anny'"),
    ({"trans": np.zeros((3, 3))}, ShapeError, "key 'trans': expected (2, 3), got (3, 3)"),
    ({"pose": np.zeros((2, 4))}, ShapeError, "key 'pose': expected (T, J, 3)"),
    ({"phenotype": np.zeros(10)}, ShapeError, "key 'phenotype': expected (6,)"),
    ({"phenotype": np.array([0.5, 0.78, 0.5, 0.5, 1.5, 0.5])}, InputError, "height = 1.5 is outside"),
    ({"trans": None}, InputError, "missing key 'trans'"),
    ({"trans": np.full((2, 3), np.nan)}, InputError, "key 'trans': contains NaN"),
])
def test_bad_files_name_the_key(tmp_path, change, error, text):
    path = _write(tmp_path / "m.npz", **change)
    with pytest.raises(error) as e:
        load_anny_motion(path)
    assert text in str(e.value) and "\n" not in str(e.value)


def test_other_bodies_are_refused(tmp_path):
    smpl = tmp_path / "smpl.npz"
    np.savez(smpl, poses=np.zeros((2, 72)), betas=np.zeros(10), trans=np.zeros((2, 3)))
    assert not is_anny_motion(smpl)
    with pytest.raises(InputError, match="an SMPL motion"):
        load_anny_motion(smpl)
    path = _write(tmp_path / "m.npz")
    with pytest.raises(InputError, match="key 'bone_names'"):
        load_anny_motion(path, bone_names=("a", "b", "x", "d"))
