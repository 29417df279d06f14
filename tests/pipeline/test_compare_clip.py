"""One clip of the comparison: both paths under three lights (compare_clip), its numbers (clip_metrics)."""

import json
import math

import numpy as np
import pytest
import torch

from relightnet.pipeline.compare_clip import LIGHTS, PATHS, ClipOutputs, clip_metrics, compare_clip, source_light
from relightnet.pipeline.compare_report import json_safe
from relightnet.prt import PrtSettings

from .conftest import RES, T

pytestmark = pytest.mark.slow  # one clip through both paths with PRT, about a minute


def test_3d_path_with_the_truths_prt_reproduces_the_ground_truth(clip0, model):
    # With the ground truth's own directions (count and seed), the 3D path is the generator's renderer.
    _, meta, clip, geo = clip0
    out = compare_clip(model, clip, geo,
                       prt=PrtSettings(n_dirs=meta["prt"]["n_dirs"], seed=meta["prt"]["direction_seed"]))
    np.testing.assert_array_equal(out.alpha_3d.numpy(), clip["mask"])
    np.testing.assert_allclose(out.renders[("3d", "true")].numpy(), clip["image"], atol=1e-5, rtol=0)
    # With other directions it differs only by quadrature noise.
    other = compare_clip(model, clip, geo, prt=PrtSettings(n_dirs=64, seed=0), smoothing="none")
    m = clip["mask"] > 0
    d = np.abs(other.renders[("3d", "true")].numpy() - clip["image"])[m]
    assert 0 < d.mean() < 0.03


def test_compare_clip_outputs(clip0, model):
    _, _, clip, geo = clip0
    ticks = []
    out = compare_clip(model, clip, geo, prt=PrtSettings(n_dirs=16), smoothing="none", tick=lambda: ticks.append(1))
    assert len(ticks) == T
    assert set(out.renders) == {(p, n) for p in PATHS for n in LIGHTS}
    m = clip["mask"] > 0
    for (path, _), r in out.renders.items():
        assert r.shape == (T, RES, RES, 3) and torch.isfinite(r).all()
        assert (r.numpy()[~m] == 0).all(), path  # both paths are 0 off the person
    torch.testing.assert_close(out.lights["true"], torch.from_numpy(clip["light"]))
    assert out.lights["raw"].shape == (T, 9, 3)
    assert torch.equal(out.lights["smoothed"], out.lights["raw"]) and not out.outliers.any()
    torch.testing.assert_close(out.renders[("2d", "smoothed")], out.renders[("2d", "raw")])
    # The 2D path's input is the subject under the fixed source light: albedo ⊙ (T · L_src).
    src = np.einsum("thwk,kc->thwc", clip["transport"], source_light("studio").numpy()) * clip["albedo"]
    np.testing.assert_allclose(out.source.numpy(), src, atol=1e-5)
    # The video frames: target frame | 2D | 3D | ground truth over the clip's background.
    from relightnet.io import to_uint8
    from relightnet.pipeline.compare_report import side_by_side

    frames = side_by_side(clip, out)
    assert frames.shape == (T, RES, 4 * RES, 3) and frames.dtype == np.uint8
    np.testing.assert_array_equal(frames[:, :, :RES], clip["image_composite"])
    mk = clip["mask"][..., None]
    for t in range(T):
        gt_panel = to_uint8(torch.from_numpy(clip["image"][t] * mk[t] + clip["background"][t] * (1 - mk[t])))
        np.testing.assert_array_equal(frames[t, :, 3 * RES:], gt_panel.numpy())
    # The Hermite smoother returns a sequence of the same shape.
    sm = compare_clip(model, clip, geo, prt=PrtSettings(n_dirs=16), smoothing="hermite")
    assert sm.lights["smoothed"].shape == (T, 9, 3) and torch.isfinite(sm.lights["smoothed"]).all()
    # The 2D path relights the photo's albedo by default; cnn_albedo relights the CNN's. The 3D path
    # does not change.
    cnn = compare_clip(model, clip, geo, prt=PrtSettings(n_dirs=16), smoothing="none", cnn_albedo=True)
    torch.testing.assert_close(cnn.renders[("3d", "true")], out.renders[("3d", "true")])
    assert not torch.allclose(cnn.renders[("2d", "true")], out.renders[("2d", "true")])


def test_clip_metrics_are_exact_for_a_perfect_output(clip0):
    _, _, clip, _ = clip0
    gt = torch.from_numpy(clip["image"])
    mask = torch.from_numpy(clip["mask"])
    light = torch.from_numpy(clip["light"])
    renders = {(p, n): gt.clone() for p in PATHS for n in LIGHTS}
    renders[("3d", "raw")] = gt + 0.5 * mask[..., None]  # a known error (after clipping and sRGB encoding)
    no = torch.zeros(T, dtype=torch.bool)
    out = ClipOutputs({"true": light, "raw": light * 1.1, "smoothed": light.clone()}, renders, mask, gt, no, no)
    rec = clip_metrics(out, gt, mask)
    rows = {(r["path"], r["light"]): r for r in rec["rows"]}
    assert len(rows) == 6
    r = rows[("2d", "true")]
    assert r["rmse"] == 0 and math.isinf(r["psnr"]) and r["ssim"] == 1 and r["temporal"] == 0
    assert len(r["per_frame"]["rmse"]) == T and len(r["per_frame"]["temporal"]) == T - 1
    from relightnet.color import linear_to_srgb

    err = linear_to_srgb((gt + 0.5).clamp(0, 1)) - linear_to_srgb(gt.clamp(0, 1))
    per_frame = [math.sqrt(float((err[t][mask[t] > 0] ** 2).mean())) for t in range(T)]
    assert rows[("3d", "raw")]["per_frame"]["rmse"] == pytest.approx(per_frame, rel=1e-5)
    assert rows[("3d", "raw")]["rmse"] == pytest.approx(np.mean(per_frame), rel=1e-5)
    assert rec["light"]["smoothed"]["error"] == 0 and rec["light"]["raw"]["error"] > 0
    assert rec["light"]["raw"]["relative"] == pytest.approx(0.1, rel=1e-6)
    assert rec["light"]["true"]["jitter"] >= 0 and rec["mask_iou_3d"] == 1.0
    # JSON: +inf is written as the string "inf" (strict JSON, no Infinity token).
    text = json.dumps(json_safe(rec), allow_nan=False)
    assert json.loads(text)["rows"][0]["psnr"] == "inf" and float("inf") == float(json.loads(text)["rows"][0]["psnr"])


def test_source_light_is_exposed_at_its_level():
    from relightnet.data.lights import light_level
    from relightnet.light import preset_light

    L = source_light("studio", 2, level=0.5)
    assert L.shape == (9, 3) and L.dtype == torch.float32
    assert light_level(L) == pytest.approx(0.5, rel=1e-5)
    ratio = L / preset_light("studio", 2)
    torch.testing.assert_close(ratio, torch.full_like(ratio, float(ratio[0, 0])))  # a scaled preset
    assert source_light("studio", 3).shape == (16, 3)
