import math

import pytest
import torch
import torch.nn.functional as F

from relightnet.checks import InputError
from relightnet.color import linear_to_srgb
from relightnet.data.augment import (
    Augment,
    crop,
    hflip,
    mirror_directions,
    mirror_label_map,
    resize,
    scale_intensity,
    sh_mirror_signs,
    white_balance,
)
from relightnet.sh import irradiance, sh_basis


def _shading(s):
    """(3, H, W) T·L of a CNN-layout sample."""
    return torch.einsum("khw,kc->chw", s["transport"], s["light"])


def _sample(h=32, w=48, lmax=2, seed=0):
    """A consistent random sample: image = albedo ⊙ (T·L), with the unshadowed transport of real normals."""
    g = torch.Generator().manual_seed(seed)
    k = (lmax + 1) ** 2
    n = F.normalize(torch.randn(h, w, 3, generator=g, dtype=torch.float64), dim=-1)
    occl = torch.rand(h, w, 1, generator=g, dtype=torch.float64)
    A = torch.tensor([math.pi, 2 * math.pi / 3, math.pi / 4] + [0.0] * 6, dtype=torch.float64)
    band = torch.tensor([l for l in range(lmax + 1) for _ in range(2 * l + 1)])
    T = sh_basis(n, lmax) * A[band] * occl  # (H, W, K)
    light = torch.randn(k, 3, generator=g, dtype=torch.float64) * 0.3
    light[0] += 1.5
    albedo = torch.rand(h, w, 3, generator=g, dtype=torch.float64)
    img = albedo * (T @ light)
    mask = (torch.rand(h, w, generator=g) > 0.3).double()
    parts = torch.randint(0, 4, (h, w), generator=g, dtype=torch.uint8)
    srgb = (linear_to_srgb(img.clamp(0, 1)) * 255).round().to(torch.uint8)
    cf = lambda x: x.permute(2, 0, 1).contiguous()  # noqa: E731
    return {"image": cf(img), "albedo": cf(albedo), "transport": cf(T), "transport_unoccluded": cf(T / occl),
            "light": light, "normals": cf(n), "mask": mask[None], "parts": parts[None], "depth": mask[None] * 3,
            "image_srgb": cf(srgb), "background": cf(torch.rand(h, w, 3, generator=g, dtype=torch.float64))}


def _consistent(s, atol=1e-9):
    return torch.allclose(s["image"], s["albedo"] * _shading(s), atol=atol)


@pytest.mark.parametrize("lmax", [0, 1, 2, 3, 4, 6])
def test_mirror_signs_match_basis(lmax):
    d = F.normalize(torch.randn(500, 3, dtype=torch.float64), dim=-1)
    signs = sh_mirror_signs((lmax + 1) ** 2, torch.float64)
    assert torch.allclose(sh_basis(mirror_directions(d), lmax), sh_basis(d, lmax) * signs, atol=1e-12)


def test_mirror_signs_order2():
    assert torch.nonzero(sh_mirror_signs(9) < 0).flatten().tolist() == [1, 4, 5]
    with pytest.raises(InputError):
        sh_mirror_signs(8)


def test_hflip_keeps_shading_and_consistency():
    s = _sample()
    f = hflip(s)
    # Shading at the mirrored pixel is unchanged: flip(T)·flip(L) == T·L flipped.
    assert torch.allclose(_shading(f), _shading(s).flip(-1), atol=1e-12)
    assert _consistent(f)
    # The flipped transport is the transport of the mirrored normals (closed form, no occlusion).
    tu = torch.einsum("khw->hwk", f["transport_unoccluded"])
    n_m = torch.einsum("chw->hwc", f["normals"])
    A = torch.tensor([math.pi] + [2 * math.pi / 3] * 3 + [math.pi / 4] * 5, dtype=torch.float64)
    assert torch.allclose(tu, sh_basis(n_m, 2) * A, atol=1e-9)
    # Irradiance of the mirrored light at mirrored normals equals the original.
    n = torch.einsum("chw->hwc", s["normals"])
    assert torch.allclose(irradiance(f["light"], mirror_directions(n)), irradiance(s["light"], n), atol=1e-9)
    # Twice is the identity; the input is left alone.
    ff = hflip(f)
    for k in s:
        assert torch.equal(ff[k], s[k]), k
    assert not torch.equal(f["image"], s["image"])


def test_hflip_sequences_and_labels():
    s = _sample(h=16, w=16)
    clip = {k: torch.stack([v, v * 1]) for k, v in s.items()}  # (T, ...)
    f = hflip(clip)
    assert f["transport"].shape == (2, 9, 16, 16) and f["light"].shape == (2, 9, 3)
    assert torch.allclose(f["transport"][1], hflip(s)["transport"])
    assert torch.allclose(f["light"][0], hflip(s)["light"])
    lm = mirror_label_map(["body", "hand.R", "hand.L", "head"])
    assert lm.tolist() == [0, 2, 1, 3]
    assert mirror_label_map(["left_arm", "right_arm", "torso"]).tolist() == [1, 0, 2]
    p = hflip(s, label_map=lm)["parts"]
    assert torch.equal(p, lm[s["parts"].long()].to(torch.uint8).flip(-1))


def test_crop_resize_photometric_keep_identity():
    s = _sample(h=40, w=40)
    c = crop(s, 3, 5, 32, 16)
    assert c["image"].shape == (3, 32, 16) and c["transport"].shape == (9, 32, 16) and _consistent(c)
    assert torch.equal(c["light"], s["light"])
    r = resize(c, 48)
    assert r["mask"].shape == (1, 48, 48) and r["parts"].dtype == torch.uint8 and _consistent(r)
    rb = resize(s, (20, 20), mode="bilinear")
    assert rb["image"].shape == (3, 20, 20)
    # Labels stay labels (nearest); images are smooth averages within the input range.
    assert set(rb["parts"].unique().tolist()) <= set(s["parts"].unique().tolist())
    assert rb["image"].min() >= s["image"].min() - 1e-9 and rb["image"].max() <= s["image"].max() + 1e-9
    i = scale_intensity(s, 2.5)
    assert torch.allclose(i["image"], 2.5 * s["image"]) and torch.equal(i["albedo"], s["albedo"]) and _consistent(i)
    assert torch.allclose(i["background"], 2.5 * s["background"])
    w = white_balance(s, [1.2, 1.0, 0.8])
    assert torch.allclose(w["light"][:, 2], 0.8 * s["light"][:, 2]) and _consistent(w)
    assert w["image_srgb"].dtype == torch.uint8
    assert w["image_srgb"][2].float().mean() < s["image_srgb"][2].float().mean()
    with pytest.raises(InputError):
        crop(s, 30, 0, 32, 8)
    with pytest.raises(InputError):
        scale_intensity(s, -1)
    with pytest.raises(InputError):
        white_balance(s, [1, 0, 1])


def test_random_augment_keeps_identity_and_multiples():
    s = _sample(h=64, w=64)
    aug = Augment(flip=0.5, crop_scale=(0.5, 1.0), intensity=(0.5, 2.0), white_balance=0.2)
    seen_flip = set()
    for seed in range(12):
        a = aug(s, torch.Generator().manual_seed(seed))
        h, w = a["image"].shape[-2:]
        assert h % 16 == 0 and w % 16 == 0 and 32 <= h <= 64
        assert all(a[k].shape[-2:] == (h, w) for k in ("mask", "transport", "parts", "normals"))
        assert _consistent(a)
        seen_flip.add(bool((a["light"][1] * s["light"][1] < 0).all()))
    assert seen_flip == {True, False}
    a1 = aug(s, torch.Generator().manual_seed(3))
    a2 = aug(s, torch.Generator().manual_seed(3))
    assert all(torch.equal(a1[k], a2[k]) for k in a1)
    r = Augment(crop_scale=(0.6, 0.9), size=40, multiple=16)(s, torch.Generator().manual_seed(0))
    assert r["image"].shape == (3, 32, 32) and _consistent(r)
    with pytest.raises(InputError):
        Augment(flip=2)
