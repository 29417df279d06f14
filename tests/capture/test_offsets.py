"""Offsets solved from silhouettes: a body grown by a known field, seen turning, is grown back."""

import math

import pytest
import torch

from relightnet.capture.offsets import OffsetFit, apply_offsets, solve_offsets
from relightnet.errors import InputError
from relightnet.fit import FitBody, FitResult, default_intrinsics
from relightnet.fit.body_model import FIT_BONES
from relightnet.fit.masks import PackedMasks
from relightnet.fit.preview import fit_camera, fit_meshes
from relightnet.raster import rasterize

SIZE = (160, 160)  # the person ~140 px tall: 1 px ≈ 1.2 cm at the body


@pytest.fixture(scope="module")
def fit_body(anny_body):
    return FitBody(anny_body)


@pytest.fixture(scope="module")
def turning(fit_body):
    """A body in its rest pose turning a full circle in 4 frames, and its torso (V,) bool."""
    from relightnet.body.albedo import REGIONS, region_labels

    T = 4
    pose = torch.zeros(T, len(FIT_BONES), 3)
    pose[:, 0, 1] = 0.3 + torch.arange(T) * (2 * math.pi / T)
    trans = torch.tensor([0.0, -0.85, -2.8]).expand(T, 3).clone()
    res = FitResult(pose, trans, fit_body.body.phenotype_tensor(None)[0], default_intrinsics(SIZE, 40.0), SIZE,
                    torch.zeros(T), torch.zeros(T, dtype=torch.bool), 0.0)
    torso = region_labels(fit_body.body, sleeves="none", legs="shorts") == REGIONS.index("top")
    return res, torso


def _silhouettes(res, fb, offsets):
    out = fit_meshes(res, fb)
    cam = fit_camera(res, out.verts.shape[0])
    return rasterize(cam.transform(apply_offsets(out.verts, out.normals, offsets)), out.faces, res.size).mask.float()


@pytest.mark.slow
def test_a_grown_torso_is_grown_back(fit_body, turning):
    res, torso = turning
    masks = _silhouettes(res, fit_body, torch.where(torso, 0.04, 0.0))
    fit = solve_offsets(res, fit_body, masks)
    d = fit.offsets
    assert isinstance(fit, OffsetFit) and d.shape == (fit_body.body.num_verts,) and d.dtype == torch.float32
    assert fit.frames == (0, 1, 2, 3)
    # the truth scores 1; offsets near 0 already lose ~0.02 to where the edge pixels' centres fall
    # (test below), the bare body (torso 4 cm = 3 px short each side) scores 0.93
    assert fit.iou_body < 0.94 and fit.iou_offset > fit.iou_body + 0.02 and fit.iou_offset > 0.95
    assert abs(float(d[torso].median()) - 0.04) < 0.015
    assert float(d[~torso].abs().median()) < 0.005
    from relightnet.capture.offsets import SKIN_BOUND, _skin

    s = _skin(fit_body.body)  # the default skin: the face and the hands, held within ±1 cm
    assert 0 < int(s.sum()) < len(d) and not bool((s & torso).any()) and float(d[s].abs().max()) <= SKIN_BOUND + 1e-6
    assert float(d.min()) >= -0.01 - 1e-6 and float(d.max()) <= 0.12 + 1e-6


@pytest.mark.slow
def test_the_body_s_own_silhouettes_give_small_offsets(fit_body, turning):
    res, _ = turning
    masks = PackedMasks.from_masks(_silhouettes(res, fit_body, torch.zeros(fit_body.body.num_verts)))
    fit = solve_offsets(res, fit_body, masks, bound=0.05)
    assert fit.iou_body > 0.999 and fit.iou_offset > 0.95
    assert float(fit.offsets.abs().median()) < 0.005 and float(fit.offsets.max()) <= 0.05 + 1e-6


def test_frames_without_a_person_are_skipped(fit_body, turning):
    res, _ = turning
    masks = _silhouettes(res, fit_body, torch.zeros(fit_body.body.num_verts))
    masks[1] = 0
    res2 = FitResult(res.pose, res.trans, res.phenotype, res.intrinsics, res.size, res.residual_2d,
                     torch.tensor([False, False, True, False]), 0.0)
    assert solve_offsets(res2, fit_body, masks, iters=3).frames == (0, 3)
    assert solve_offsets(res2, fit_body, masks, n_frames=1, iters=3).frames == (0,)  # a photo


def test_bad_input_is_one_line(fit_body, turning):
    res, _ = turning
    with pytest.raises(InputError, match="no frame shows the person") as e:
        solve_offsets(res, fit_body, torch.zeros(4, *SIZE))
    assert "\n" not in str(e.value)
    with pytest.raises(InputError, match=r"masks: expected \(4, 160, 160\)") as e:
        solve_offsets(res, fit_body, torch.zeros(4, 80, 80))
    assert "\n" not in str(e.value)
    with pytest.raises(InputError, match="masks: expected 4 masks"):
        solve_offsets(res, fit_body, PackedMasks.from_masks(torch.ones(3, *SIZE)))
