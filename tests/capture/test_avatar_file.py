"""The avatar file: arrays only, versioned, every wrong key a one-line error naming it."""

import numpy as np
import pytest
import torch

from relightnet.capture import CapturedAvatar, load_avatar, save_avatar
from relightnet.capture.avatar_file import VERSION
from relightnet.checks import InputError


def _avatar(v=50, s=16):
    g = torch.Generator().manual_seed(0)
    return CapturedAvatar(torch.rand(s, s, 3, generator=g), torch.rand(s, s, generator=g),
                          torch.randint(0, 3, (s, s), generator=g).to(torch.int8), 0.02 * torch.rand(v, generator=g),
                          torch.tensor([0.5, 0.78, 0.5, 0.5, 0.37, 0.5]), 0.9, 12)


def _rewrite(path, **change):
    raw = dict(np.load(path, allow_pickle=False))
    for k, v in change.items():
        if v is None:
            raw.pop(k)
        else:
            raw[k] = v
    np.savez(path, **raw)


def test_round_trip(tmp_path):
    a = _avatar()
    p = save_avatar(tmp_path / "me.avatar.npz", a)
    b = load_avatar(p, num_verts=50)
    assert torch.allclose(b.texture, a.texture, atol=1e-3) and torch.allclose(b.offsets, a.offsets)
    assert torch.equal(b.filled, a.filled) and b.frames == 12 and b.seen_share == pytest.approx(0.9)
    assert list(tmp_path.iterdir()) == [p]  # nothing else left behind


@pytest.mark.parametrize("change, match", [
    ({"version": np.int32(VERSION + 1)}, "key 'version'"),
    ({"format": np.array("something")}, "key 'format'"),
    ({"body_model": np.array("smpl")}, "key 'body_model'"),
    ({"texture": None}, "key 'texture'"),
    ({"offsets": np.zeros(49, np.float32)}, "key 'offsets'"),
    ({"offsets": np.full(50, 3.0, np.float32)}, "key 'offsets'"),
    ({"confidence": np.zeros((8, 8), np.float16)}, "key 'confidence'"),
    ({"phenotype": np.full(6, 7.0, np.float32)}, "key 'phenotype'"),
    ({"texture": np.full((16, 16, 3), np.nan, np.float16)}, "key 'texture'"),
    ({"frames": np.array([1, 2])}, "key 'frames'"),
])
def test_a_wrong_file_is_one_line_naming_the_key(tmp_path, change, match):
    p = save_avatar(tmp_path / "me.avatar.npz", _avatar())
    _rewrite(p, **change)
    with pytest.raises(InputError, match=match) as e:
        load_avatar(p)
    assert "\n" not in str(e.value)


def test_another_body_a_pickle_and_garbage_are_refused(tmp_path):
    p = save_avatar(tmp_path / "me.avatar.npz", _avatar())
    with pytest.raises(InputError, match="50 vertices"):
        load_avatar(p, num_verts=13718)
    obj = tmp_path / "obj.avatar.npz"
    np.savez(obj, format=np.array([{"a": 1}], dtype=object))
    with pytest.raises(InputError):
        load_avatar(obj)
    junk = tmp_path / "junk.avatar.npz"
    junk.write_bytes(b"not a zip at all")
    with pytest.raises(InputError, match="junk.avatar.npz"):
        load_avatar(junk)
    with pytest.raises(InputError, match=".avatar.npz"):
        save_avatar(tmp_path / "me.npz", _avatar())
