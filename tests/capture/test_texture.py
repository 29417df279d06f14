"""The de-lit texture: a person rendered under a known light and captured back gives their albedo."""

import math

import numpy as np
import pytest
import torch

from relightnet.capture import TextureOptions, capture_person
from relightnet.capture.metrics import surface_texels
from relightnet.capture.texture import TexelSamples, TextureFusion, weighted_median
from relightnet.checks import InputError, ShapeError
from relightnet.color import linear_to_srgb
from relightnet.fit import FitBody, FitResult, default_intrinsics
from relightnet.fit.body_model import FIT_BONES
from relightnet.fit.preview import fit_camera, fit_meshes
from relightnet.light import ambient_light, directional_light
from relightnet.prt import PrtSettings, vertex_transport
from relightnet.render.frame import TexturedAlbedo, render_mesh

SIZE = (384, 288)
TEX = 256


@pytest.fixture(scope="module")
def turning(anny_body):
    """A painted Anny turning a full circle in 8 frames, rendered in the fit's own camera, and the truth."""
    from relightnet.body.albedo import region_labels
    from relightnet.data.textures import paint_albedo, sample_outfit, uv_atlas

    fb = FitBody(anny_body)
    T = 8
    pose = torch.zeros(T, len(FIT_BONES), 3)
    pose[:, 0, 1] = torch.arange(T) * (2 * math.pi / T)
    trans = torch.tensor([0.0, -0.85, -3.4]).expand(T, 3).clone()
    res = FitResult(pose, trans, anny_body.phenotype_tensor(None)[0], default_intrinsics(SIZE, 40.0), SIZE,
                    torch.zeros(T), torch.zeros(T, dtype=torch.bool), 0.0)
    atlas = uv_atlas(anny_body, TEX)
    outfit = sample_outfit(np.random.default_rng(4))
    tex = paint_albedo(atlas, region_labels(anny_body, sleeves=outfit["sleeves"], legs=outfit["legs"]), outfit)
    light = ambient_light(0.25) + directional_light(torch.tensor([1.0, 0.5, 0.6]), 0.7)
    cam, frames, masks = fit_camera(res), [], []
    for t in range(T):
        out = fit_meshes(res, fb, t, t + 1)
        v, n = out.verts[0], out.normals[0]
        r = render_mesh(v, out.faces, vertex_transport(v, out.faces, n, prt=PrtSettings(n_dirs=64)),
                        TexturedAlbedo(tex, anny_body.uv, anny_body.uv_faces), light, cam)
        frames.append(linear_to_srgb(r.image[0].clamp(0, 1)).permute(2, 0, 1))
        masks.append(r.alpha[0] > 0.5)
    return fb, res, atlas, tex, light, frames, masks


def _rel_rmse(a, b):
    s = (a * b).sum() / (a * a).sum()
    return float((s * a - b).square().mean().sqrt() / b.square().mean().sqrt()), float(s)


@pytest.mark.slow
def test_a_known_light_gives_the_albedo_back(turning):
    """De-lit by the light it was rendered under, the texture is the true albedo over the texels seen: the
    typical texel within a few percent, the RMSE left at the texture's edges (hairline, stripes, hands: a
    384-px person resamples a 256² texture, which blurs an edge by about a texel); the raw colours are further off."""
    fb, res, atlas, tex, light, frames, masks = turning
    T = len(frames)
    cr = capture_person(res, fb, iter(frames), iter(masks), light.expand(T, 9, 3), options=TextureOptions(size=TEX),
                        raw=True, atlas=atlas)
    m = (cr.seen & surface_texels(atlas).view(TEX, TEX)).reshape(-1)
    err, scale = _rel_rmse(cr.avatar.texture.reshape(-1, 3)[m], tex.reshape(-1, 3)[m])
    raw_err, _ = _rel_rmse(cr.raw_texture.reshape(-1, 3)[m], tex.reshape(-1, 3)[m])
    assert cr.avatar.seen_share > 0.75  # 8 views 45° apart: not the soles, the crown, the inner arms or clipped skin
    assert abs(scale - 1) < 0.05  # the exposure is kept: no global scale is needed
    a, b = cr.avatar.texture.reshape(-1, 3)[m] * scale, tex.reshape(-1, 3)[m]
    typical = float(((a - b).abs().sum(1) / b.sum(1).clamp_min(0.05)).median())
    assert err < 0.18 and raw_err > 1.4 * err and typical < 0.06
    assert cr.avatar.frames == T and bool((cr.avatar.filled == 0).any()) and bool((cr.avatar.filled == 2).any())
    assert cr.avatar.texture.shape == (TEX, TEX, 3) and float(cr.avatar.texture.min()) >= 0


def test_frames_without_the_person_and_bad_counts(turning):
    fb, res, atlas, tex, light, frames, masks = turning
    T = len(frames)
    with pytest.raises(InputError, match="no frame shows"):
        capture_person(res, fb, iter(frames), iter([None] * T), light.expand(T, 9, 3), atlas=atlas,
                       options=TextureOptions(size=TEX))
    with pytest.raises(InputError, match="3 frames"):
        capture_person(res, fb, iter(frames[:3]), iter(masks[:3]), light.expand(T, 9, 3), atlas=atlas,
                       options=TextureOptions(size=TEX))
    with pytest.raises(ShapeError):
        capture_person(res, fb, iter(frames), iter(masks), light.expand(T - 1, 9, 3), atlas=atlas,
                       options=TextureOptions(size=TEX))


def test_weighted_median_and_the_top_k_fusion():
    v = torch.tensor([[[1.0], [2.0], [10.0]]])
    assert weighted_median(v, torch.tensor([[1.0, 1.0, 1.0]])).item() == 2.0
    assert weighted_median(v, torch.tensor([[0.1, 0.1, 5.0]])).item() == 10.0  # the heavy sample wins
    assert weighted_median(v, torch.zeros(1, 3)).item() == 0.0
    fusion = TextureFusion(2, top_k=2)
    for w, val in ((0.5, 1.0), (0.9, 2.0), (0.1, 50.0), (0.8, 3.0)):  # the 0.1 outlier is not kept
        fusion.add(TexelSamples(torch.tensor([0]), torch.full((1, 3), val), torch.full((1, 3), val),
                                torch.tensor([w])))
    assert sorted(fusion.weight[0].tolist()) == pytest.approx([0.8, 0.9])
    out = fusion.result()
    assert out[0, 0].item() in (2.0, 3.0) and out[1].abs().sum() == 0
    assert fusion.total[0].item() == pytest.approx(2.3) and int(fusion.frames[0]) == 4
    with pytest.raises(InputError):
        fusion.result("raw")


def test_options_are_checked():
    for bad in ({"size": 10}, {"size": 100.5}, {"top_k": 0}, {"n_dirs": 2}):
        with pytest.raises(InputError):
            TextureOptions(**bad)
