import json
import math

import numpy as np
import pytest
import torch

from relightnet.body.albedo import REGIONS
from relightnet.checks import InputError
from relightnet.data.config import SynthConfig
from relightnet.data.generate import GENERATOR_VERSION, Sample, generate_sample, generate_sequence, prepare_assets
from relightnet.data.lights import LUMA
from relightnet.sh import sh_basis
from relightnet.sh.irradiance import cosine_lobe_per_coeff

RES = 64
CFG = SynthConfig(res=RES, n_dirs=24, partial_crop_prob=0.0)
N = 6
FLOAT_FIELDS = {  # name -> trailing shape
    "image": (RES, RES, 3), "mask": (RES, RES), "albedo": (RES, RES, 3), "transport": (RES, RES, 9),
    "transport_unoccluded": (RES, RES, 9), "light": (9, 3), "normals": (RES, RES, 3), "depth": (RES, RES),
    "background": (RES, RES, 3),
}
UINT8_FIELDS = {"image_srgb": (RES, RES, 3), "image_composite": (RES, RES, 3), "parts": (RES, RES)}


pytestmark = pytest.mark.usefixtures("one_thread")  # tests/data/conftest.py


@pytest.fixture(scope="module")
def assets(anny_body):
    return prepare_assets(anny_body, texture_size=128)


@pytest.fixture(scope="module")
def samples(assets):
    return [generate_sample(CFG, "train", i, assets) for i in range(N)]


def _shading(a):
    return np.einsum("hwk,kc->hwc", a["transport"].astype(np.float64), a["light"].astype(np.float64))


def test_fields_shapes_dtypes_and_meta(samples):
    for s in samples:
        assert isinstance(s, Sample)
        assert set(s.arrays) == set(FLOAT_FIELDS) | set(UINT8_FIELDS)
        for k, shape in FLOAT_FIELDS.items():
            assert s.arrays[k].shape == shape and s.arrays[k].dtype == np.float32, k
            assert np.isfinite(s.arrays[k]).all(), k
        for k, shape in UINT8_FIELDS.items():
            assert s.arrays[k].shape == shape and s.arrays[k].dtype == np.uint8, k
        m = s.meta
        json.dumps(m)
        assert m["generator_version"] == GENERATOR_VERSION
        assert m["seed"] == {"seed": CFG.seed, "split": "train", "index": samples.index(s)}
        assert set(m["flags"]) == {"bounce", "noise_std"} and m["flags"] == {"bounce": False, "noise_std": 0.0}
        assert len(m["camera"]["intrinsics"]) == 4 and np.array(m["camera"]["world_to_camera"]).shape == (4, 4)
        assert set(m["phenotype"]) == {"gender", "age", "muscle", "weight", "height", "proportions"}
        assert m["pose"]["type"] in ("preset", "motion") and "perturbation" in m["pose"]


def test_image_is_albedo_times_transport_dot_light(samples):
    for s in samples:
        a = s.arrays
        m = a["mask"] > 0
        expect = a["albedo"] * _shading(a)
        assert np.abs(a["image"] - expect)[m].max() < 1e-5
        assert (a["image"][~m] == 0).all()
        # The 8-bit image is the sRGB encoding of the linear one.
        from relightnet.io.image import to_uint8

        assert np.array_equal(to_uint8(torch.from_numpy(a["image"])).numpy(), a["image_srgb"])


def test_mask_albedo_parts_depth_normals(samples):
    seen = set()
    for s in samples:
        a = s.arrays
        m = a["mask"] > 0
        assert set(np.unique(a["mask"])) <= {0.0, 1.0} and m.mean() > 0.05
        alb = a["albedo"][m]
        assert alb.min() >= np.float32(0.02) - 1e-6 and alb.max() <= np.float32(0.9) + 1e-6
        assert (a["albedo"][~m] == 0).all()
        assert ((a["parts"] > 0) == m).all() and a["parts"].max() <= len(REGIONS)
        seen |= set(np.unique(a["parts"][m]).tolist())
        assert len(np.unique(a["parts"][m])) >= 3
        assert (a["depth"][m] > 1.0).all() and (a["depth"][~m] == 0).all()
        n = a["normals"][m]
        assert np.allclose(np.linalg.norm(n, axis=1), 1, atol=1e-4) and (a["normals"][~m] == 0).all()
        # Light frame of the camera: x points toward the camera, so visible surfaces have n_x > 0.
        assert n[:, 0].mean() > 0.4 and (n[:, 0] > -0.2).mean() > 0.97
    assert seen >= {1, 3, 4, 5}  # skin, top, bottom, shoes across the samples


def test_unoccluded_transport_matches_the_closed_form(assets):
    # Quadrature (n_dirs) + interpolation error: at 64 directions the mean |Δ| is ~0.006 and
    # 99 % of the pixels are within ~0.035 (T_0 ≈ 0.89 facing any light); a few pixels at
    # creases (fingers, eyelids), where vertex normals disagree within a triangle, reach ~0.25.
    cfg = CFG.replace(n_dirs=64)
    s = generate_sample(cfg, "val", 0, assets)
    a = s.arrays
    m = a["mask"] > 0
    n = torch.from_numpy(a["normals"][m]).double()
    closed = (sh_basis(n, 2) * cosine_lobe_per_coeff(2, dtype=torch.float64)).numpy()
    d = np.abs(a["transport_unoccluded"][m] - closed)
    assert d.mean() < 0.01 and np.percentile(d, 99) < 0.06 and d.max() < 0.4


def test_occlusion_only_removes_light_in_the_dc_band(samples):
    for s in samples:
        a = s.arrays
        m = a["mask"] > 0
        occ, unocc = a["transport"][m, 0], a["transport_unoccluded"][m, 0]
        assert (occ <= unocc + 1e-5).all()
        assert (occ < unocc - 0.05).mean() > 0.05  # self-occlusion does happen
        assert (occ >= -1e-6).all()


def test_determinism(assets, samples):
    again = generate_sample(CFG, "train", 2, assets)
    for k, v in samples[2].arrays.items():
        assert v.tobytes() == again.arrays[k].tobytes(), k
    assert again.meta == samples[2].meta
    for k in ("image", "albedo", "light"):
        assert not np.array_equal(samples[0].arrays[k], samples[1].arrays[k])
    other = generate_sample(CFG.replace(seed=1), "train", 2, assets)
    assert not np.array_equal(other.arrays["image"], samples[2].arrays["image"])


@pytest.mark.slow
def test_test_split_uses_only_the_test_maps(assets):
    cfg = CFG.replace(res=32, n_dirs=8, synthetic_light_prob=0.0)
    for split, allowed in (("test", set(cfg.hdri_test)), ("train", set(cfg.hdri_train)), ("val", set(cfg.hdri_train))):
        for i in range(5):
            m = generate_sample(cfg, split, i, assets).meta
            assert m["light"]["source"] == "hdri" and m["light"]["hdri"] in allowed
            if m["background"]["kind"] == "envmap":
                assert m["background"]["hdri"] in allowed


def test_full_body_crop_keeps_the_padding(samples):
    for s in samples:
        m = s.arrays["mask"] > 0
        rows, cols = np.nonzero(m)
        # Margin >= pad·res / ((1 + 2 pad)(1 + 2 jitter)) pixels (framing.py), minus a pixel.
        margin = CFG.pad * RES / ((1 + 2 * CFG.pad) * (1 + 2 * CFG.jitter)) - 1
        assert rows.min() >= margin and cols.min() >= margin
        assert rows.max() <= RES - 1 - margin and cols.max() <= RES - 1 - margin
        assert s.meta["camera"]["crop_mode"] == "full"
        assert max(rows.max() - rows.min(), cols.max() - cols.min()) > 0.75 * RES  # the body fills the crop


def test_partial_crops_and_views(assets):
    cfg = CFG.replace(res=32, n_dirs=8, partial_crop_prob=1.0)
    modes = {generate_sample(cfg, "train", i, assets).meta["camera"]["crop_mode"] for i in range(6)}
    assert modes == {"upper", "head"}


@pytest.mark.slow
def test_variety_of_bodies_poses_lights_and_views(samples, assets):
    metas = [s.meta for s in samples] + [generate_sample(CFG.replace(res=16, n_dirs=8), "train", i, assets).meta
                                         for i in range(N, 3 * N)]
    # prt_reuse = 4: four consecutive stills share a person and pose (and its PRT), nothing else.
    groups = {}
    for i, m in enumerate(metas):
        assert m["prt"]["reuse"] == {"group": i // 4, "member": i % 4, "size": 4}
        groups.setdefault(i // 4, []).append(m)
    assert len({round(m["phenotype"]["gender"], 3) for m in metas}) == len(groups)
    for g in groups.values():
        assert len({json.dumps([m["phenotype"], m["pose"]["name"], m["garments"]]) for m in g}) == 1
        assert len({m["pose"]["yaw_deg"] for m in g}) == len(g)
        assert len({m["light"]["rotation_deg"] for m in g}) == len(g)
        assert len({m["camera"]["distance"] for m in g}) == len(g)
    assert len({m["pose"]["name"] for m in metas}) >= 4
    assert len({m["light"]["source"] for m in metas}) >= 2
    yaws = np.array([m["pose"]["yaw_deg"] for m in metas])
    assert (np.abs(yaws) < 35).mean() > 0.3 and (np.abs(yaws) > 35).any()


def test_bounce_is_flagged_grey_and_adds_light(assets):
    base = generate_sample(CFG, "train", 3, assets)
    b = generate_sample(CFG.replace(bounce_prob=1.0), "train", 3, assets)
    assert b.meta["flags"]["bounce"] and not base.meta["flags"]["bounce"]
    a = b.arrays
    m = a["mask"] > 0
    assert a["transport"].shape == (RES, RES, 9)  # still scalar per coefficient (grey reflectors)
    assert np.abs(a["image"] - a["albedo"] * _shading(a))[m].max() < 1e-5
    d = a["transport"][..., 0] - base.arrays["transport"][..., 0]
    assert (d[m] >= -1e-5).all() and d[m].max() > 0.01
    assert np.array_equal(a["transport_unoccluded"], base.arrays["transport_unoccluded"])


def test_noise_is_flagged_and_only_on_the_subject(assets):
    s = generate_sample(CFG.replace(noise_std=0.05), "train", 1, assets)
    a = s.arrays
    m = a["mask"] > 0
    assert s.meta["flags"]["noise_std"] == 0.05
    r = a["image"] - a["albedo"] * _shading(a)
    assert abs(r[m].std() - 0.05) < 0.005 and (r[~m] == 0).all()


def test_composite_and_background(samples):
    for s in samples:
        a = s.arrays
        m = a["mask"] > 0
        assert (a["background"] >= 0).all()
        from relightnet.io.image import to_uint8

        bg8 = to_uint8(torch.from_numpy(a["background"])).numpy().astype(int)
        far = np.ones_like(m)
        far[1:-1, 1:-1] = ~(m[:-2, 1:-1] | m[2:, 1:-1] | m[1:-1, :-2] | m[1:-1, 2:] | m[1:-1, 1:-1])
        far &= ~m
        assert np.abs(a["image_composite"].astype(int) - bg8)[far].max() <= 1  # background away from edges
        inner = m.copy()
        inner[1:-1, 1:-1] &= m[:-2, 1:-1] & m[2:, 1:-1] & m[1:-1, :-2] & m[1:-1, 2:]
        assert np.abs(a["image_composite"].astype(int) - a["image_srgb"].astype(int))[inner].max() <= 1
        edge = m & ~inner
        assert (np.abs(a["image_composite"].astype(int) - a["image_srgb"].astype(int))[edge] > 1).any()


def test_exposure_is_sane(samples):
    means = [float((s.arrays["image"][s.arrays["mask"] > 0] @ np.array(LUMA)).mean()) for s in samples]
    assert 0.01 < min(means) and max(means) < 0.8
    for s in samples:  # few clipped pixels
        assert (s.arrays["image_srgb"][s.arrays["mask"] > 0] == 255).mean() < 0.2


@pytest.mark.slow
def test_sequence(assets):
    cfg = CFG.replace(res=32, n_dirs=8)
    T = 5
    seqs = []
    for i in range(12):
        s = generate_sequence(cfg, "train", i, T, assets)
        seqs.append(s)
        if s.meta["switch_frames"] and i >= 2:
            break
    assert any(s.meta["switch_frames"] for s in seqs), "no clip with a light switch among the first 12"
    for s in seqs:
        a, m = s.arrays, s.meta
        assert a["image"].shape == (T, 32, 32, 3) and a["light"].shape == (T, 9, 3) and a["parts"].shape == (T, 32, 32)
        assert m["kind"] == "sequence" and m["n_frames"] == T and len(m["frames"]) == T
        json.dumps(m)
        mask = a["mask"] > 0
        shading = np.einsum("thwk,tkc->thwc", a["transport"], a["light"])
        assert np.abs(a["image"] - a["albedo"] * shading)[mask].max() < 1e-5
        # One camera for the clip: the intrinsics are shared, the body moves inside the crop.
        assert all((a["mask"][t] > 0).any() for t in range(T))
        L = a["light"].astype(np.float64)
        for t in range(1, T):
            step = np.linalg.norm(L[t] - L[t - 1]) / np.linalg.norm(L[t - 1])
            if t in m["switch_frames"]:
                assert m["frames"][t]["light"] != m["frames"][t - 1]["light"]
            else:
                assert step < 0.15, (t, step)
                assert m["frames"][t]["light"] == m["frames"][t - 1]["light"]
    # Clips are deterministic and independent of the stills.
    again = generate_sequence(cfg, "train", 0, T, assets)
    assert again.arrays["image"].tobytes() == seqs[0].arrays["image"].tobytes()
    still = generate_sample(cfg, "train", 0, assets)
    assert still.meta["phenotype"] != seqs[0].meta["phenotype"]


def test_bad_inputs_raise(assets):
    with pytest.raises(InputError):
        generate_sample(CFG, "holdout", 0, assets)
    with pytest.raises(InputError):
        generate_sample(CFG, "train", -1, assets)
    with pytest.raises(InputError):
        generate_sample(CFG.to_dict(), "train", 0, assets)
    with pytest.raises(InputError):
        generate_sample(CFG, "train", 0, body="anny")
    with pytest.raises(InputError):
        generate_sequence(CFG, "train", 0, 0, assets)
    with pytest.raises(InputError, match="res"):
        generate_sample(CFG.replace(res=50), "train", 0, assets)
    with pytest.raises(InputError, match="hdri_test"):
        generate_sample(CFG.replace(hdri_test=("city",)), "test", 0, assets)
    with pytest.raises(InputError, match="bounce_prob"):
        generate_sample(CFG.replace(bounce_prob=1.5), "train", 0, assets)
    assert math.isfinite(CFG.pad)
