"""The PRT-vs-Cycles comparison: metric, masks, and a tiny end-to-end run on Anny."""

import math

import pytest
import torch

from relightnet.blender import CyclesSettings
from relightnet.blender.reference import comparison_mask, front_facing, masked_rel_rmse, reference_comparison
from relightnet.checks import InputError, ShapeError
from relightnet.prt import PrtSettings
from relightnet.raster import default_camera
from relightnet.sh import save_light


def test_masked_rel_rmse():
    ref = torch.ones(4, 4, 3)
    pred = ref.clone()
    pred[0, 0] = 3.0  # outside the mask
    pred[2, 2] = 1.5
    mask = torch.zeros(4, 4, dtype=torch.bool)
    mask[1:, 1:] = True
    assert masked_rel_rmse(pred, ref, mask) == pytest.approx(math.sqrt(3 * 0.25 / 27))
    with pytest.raises(InputError, match="no pixel"):
        masked_rel_rmse(pred, ref, torch.zeros(4, 4, dtype=torch.bool))
    with pytest.raises(ShapeError):
        masked_rel_rmse(pred, ref[:3], mask)


def test_comparison_mask_and_front_facing():
    a = torch.zeros(7, 7)
    a[1:6, 1:6] = 1.0
    b = a.clone()
    b[3, 3] = 0.5
    m = comparison_mask(a, b, erode=0)
    assert int(m.sum()) == 24 and not m[3, 3]
    m1 = comparison_mask(a, a, erode=1)
    assert int(m1.sum()) == 9 and m1[2:5, 2:5].all()
    cam = default_camera(16)
    n = torch.zeros(16, 16, 3)
    n[..., 2] = 1.0  # facing +z, toward the default camera
    assert front_facing(n, cam).all() and not front_facing(-n, cam).any()
    side = torch.zeros(16, 16, 3)
    side[..., 0] = 1.0  # facing +x: seen from the front on the left half of the image only
    f = front_facing(side, cam)
    assert f[:, :8].all() and not f[:, 8:].any()


def test_tiny_reference_run(anny_body, tmp_path):
    r = reference_comparison(anny_body, {"pose": anny_body.pose("apose")}, light="sunset", bounces=(0, 1), size=48,
                             cycles=CyclesSettings(spp=16), prt=PrtSettings(n_dirs=32), repeat=1, workdir=tmp_path)
    assert [row["bounces"] for row in r.rows] == [0, 1]
    assert list(tmp_path.iterdir()) == []  # the .blend files lived in a temporary folder
    for row in r.rows:
        assert all(math.isfinite(row[k]) and row[k] > 0 for k in ("vs_sh", "vs_env", "ours_s", "cycles_env_s"))
        # At 16 spp Cycles' noise dominates; the band-limited world still agrees better than the full map.
        assert row["vs_sh"] < 0.25 and row["vs_sh"] < row["vs_env"]
    assert 0 < r.noise < 0.25 and r.settings["pixels"] > 50 and r.ours[0].shape == (48, 48, 3)
    assert all(x > 0 for x in r.settings["lift"])
    save_light(tmp_path / "l.npz", torch.eye(9, 3))
    with pytest.raises(InputError, match="environment map"):
        reference_comparison(anny_body, {}, light=str(tmp_path / "l.npz"))
