"""What people wear as geometry: the slot draws, their shares, and the pieces of posed frames."""

import json
from collections import Counter

import numpy as np
import pytest
import torch

from relightnet.body import REGIONS
from relightnet.checks import InputError
from relightnet.data.config import SynthConfig
from relightnet.data.garments import (
    DEFAULT_GARMENT_PROBS,
    GARMENT_SLOTS,
    GARMENT_TYPES,
    dress_frame,
    garment_probs,
    garment_types,
    sample_garments,
)
from relightnet.data.generate import prepare_assets
from relightnet.data.poses import sample_pose
from relightnet.data.textures import sample_outfit


@pytest.fixture(scope="module")
def assets(anny_body):
    return prepare_assets(anny_body, texture_size=64)


def _draw(seed: int, probs=None):
    rng = np.random.default_rng(seed)
    outfit = sample_outfit(rng)
    return sample_garments(rng, garment_probs(probs or {}), outfit), outfit


def test_probabilities_merge_and_validate():
    p = garment_probs({"head": {"hat": 1, "none": 3}})
    assert p["head"] == {"none": 0.75, "hat": 0.25, "hood": 0.0} and p["upper"] == pytest.approx(
        DEFAULT_GARMENT_PROBS["upper"])
    assert all(sum(v.values()) == pytest.approx(1.0) for v in garment_probs({}).values())
    for bad in ({"feet": {"none": 1}}, {"head": {"crown": 1}}, {"head": {"hat": -1}}, {"head": {"hat": 0}},
                {"head": [1]}):
        with pytest.raises(InputError, match="garment_probs"):
            garment_probs(bad)
    with pytest.raises(InputError, match="garment_probs"):
        SynthConfig(garment_probs={"hair": {"bald": 1}})
    with pytest.raises(InputError, match="prt_reuse"):
        SynthConfig(prt_reuse=0)


def test_every_type_is_worn_by_at_least_5_percent_by_default():
    n = 600
    counts = Counter(t for i in range(n) for t in garment_types(_draw(i)[0]))
    shares = {t: counts[t] / n for t in GARMENT_TYPES}
    assert min(shares.values()) >= 0.05, shares
    assert len(GARMENT_TYPES) >= 6


def test_draws_are_json_and_keep_their_order():
    g, outfit = _draw(3)
    json.dumps(g)
    assert set(GARMENT_SLOTS) <= set(g)
    # Forcing one slot does not shift the draws of the others.
    h, _ = _draw(3, {"head": {"hood": 1}})
    assert h["head"] == "hood" and h["upper"] == g["upper"] and h["looseness"] == g["looseness"]
    # Legs painted under the garment: long under trousers, bare under a skirt.
    t, o = _draw(4, {"lower": {"trousers": 1}, "upper": {"none": 1}})
    assert o["legs"] == "long"
    s, o = _draw(4, {"lower": {"skirt": 1}, "upper": {"none": 1}})
    assert o["legs"] == "shorts"
    d, _ = _draw(4, {"upper": {"dress": 1}})
    assert d["lower"] == "none" and "dress" in garment_types(d)


@pytest.mark.parametrize("choice", [("upper", "loose_top"), ("upper", "jacket"), ("upper", "open_coat"),
                                    ("upper", "dress"), ("lower", "trousers"), ("lower", "wide_trousers"),
                                    ("lower", "skirt"), ("head", "hat"), ("head", "hood"), ("hair", "volume"),
                                    ("hair", "long")])
def test_each_type_dresses_a_moving_body(assets, choice):
    slot, name = choice
    body = assets.body
    probs = {slot: {name: 1}, **({"upper": {"none": 1}} if slot == "lower" else {})}
    g, outfit = _draw(11, probs)
    if outfit["hair"] is None and slot == "hair":
        g, outfit = _draw(12, probs)
    params, _ = sample_pose(np.random.default_rng(5), n_frames=20)
    with torch.no_grad():
        out = body(pose=params["pose"], trans=params["trans"])
    tab = assets.garment_tables()
    frames, topo = [], None
    for t in (0, 10, 19):
        pieces, topo = dress_frame(g, out.verts[t], out.normals[t], body.faces, out.joints[t], tab, body, outfit, topo)
        frames.append(pieces)
    kinds = [p[0] for p in frames[0]]
    want = {"volume": "volume_hair", "long": "long_hair"}.get(name, name)
    assert want in kinds
    for t in (1, 2):  # the same pieces every frame, moved with the body
        assert [p[0] for p in frames[t]] == kinds
        for a, b in zip(frames[0], frames[t], strict=True):
            assert torch.equal(a[1].faces, b[1].faces) and a[1].verts.shape == b[1].verts.shape
    piece = frames[0][kinds.index(want)][1]
    assert torch.isfinite(piece.verts).all() and torch.allclose(piece.normals.norm(dim=1),
                                                                torch.ones(len(piece.verts)), atol=1e-4)
    assert 0 <= frames[0][kinds.index(want)][2] < len(REGIONS)
    later = frames[2][kinds.index(want)][1]
    assert not torch.equal(later.verts, piece.verts)
    if piece.source is not None:  # a shell keeps its distance to the body vertex it follows (sag aside)
        d0 = (piece.verts - out.verts[0][piece.source]).norm(dim=1)
        d2 = (later.verts - out.verts[19][piece.source]).norm(dim=1)
        assert float((d0 - d2).abs().max()) <= g["sag"] + 1e-4 and float(d0.min()) > 0.005
    else:  # a hanging surface moves with its joint
        j = body.joint_index("root" if want in ("skirt", "dress") else "head")
        shift = (later.verts.mean(0) - piece.verts.mean(0))[[0, 2]]
        torch.testing.assert_close(shift, (out.joints[19, j] - out.joints[0, j])[[0, 2]], atol=0.05, rtol=0)
