"""What people wear as geometry: the slot draws, their shares, and the pieces of posed frames."""

import json
from collections import Counter

import numpy as np
import pytest
import torch

from relightnet.body.albedo import REGIONS
from relightnet.checks import InputError
from relightnet.data.config import SynthConfig
from relightnet.data.garments import (
    DEFAULT_GARMENT_PROBS,
    GARMENT_SLOTS,
    GARMENT_TYPES,
    LAYER_GAP,
    dress_frame,
    garment_probs,
    garment_types,
    room_in_front,
    sample_garments,
    surface_samples,
)
from relightnet.data.generate import prepare_assets
from relightnet.data.poses import sample_pose
from relightnet.data.textures import sample_outfit
from relightnet.prt import make_engine


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
        free = torch.ones(len(d0), dtype=torch.bool)
        if slot == "upper":  # where the room in front is ample in both frames (not clamped to half of it)
            for t in (0, 19):
                free &= room_in_front(out.verts[t], out.normals[t], body.faces, piece.source) > 0.2
        assert float(free.float().mean()) > 0.5
        assert float((d0 - d2)[free].abs().max()) <= g["sag"] + 1e-4 and float(d0[free].min()) > 0.005
    else:  # a hanging surface moves with its joint
        j = body.joint_index("root" if want in ("skirt", "dress") else "head")
        shift = (later.verts.mean(0) - piece.verts.mean(0))[[0, 2]]
        torch.testing.assert_close(shift, (out.joints[19, j] - out.joints[0, j])[[0, 2]], atol=0.05, rtol=0)


def _dressed(assets, probs, pose):
    """The pieces (by type) of a person with hair, wearing ``probs``, in a pose (J, 3) (or a preset name)."""
    rng = np.random.default_rng(3)
    outfit = sample_outfit(rng)
    outfit["hair"] = outfit["hair"] or [0.05, 0.03, 0.02]
    g = sample_garments(rng, garment_probs(probs), outfit)
    body = assets.body
    with torch.no_grad():
        out = body(pose=body.pose(pose) if isinstance(pose, str) else pose)
    pieces, _ = dress_frame(g, out.verts[0], out.normals[0], body.faces, out.joints[0], assets.garment_tables(),
                            body, outfit)
    return {p[0]: p[1] for p in pieces}, out, g


def _outside_hits(outer: torch.Tensor, inner_v: torch.Tensor, inner_f: torch.Tensor, centre: torch.Tensor):
    """(N,) bool: outer-layer vertices (N, 3) beyond which, horizontally away from the vertical axis through
    ``centre``, the inner layer (vertices, faces) still shows up: there the layers cross."""
    rel = outer.double() - centre.double()
    rel[:, 1] = 0.0
    r = rel.norm(dim=1)
    d = (rel / r[:, None].clamp_min(1e-9)).float()
    hit = torch.from_numpy(make_engine(inner_v, inner_f).occluded((outer + 1e-5 * d).numpy(), d.numpy()))
    return hit & (r > 0.01)  # not the crown's apex on the axis


@pytest.mark.parametrize("pose", ["arms_down", "sampled"])
@pytest.mark.parametrize("probs,pairs", [
    ({"upper": {"open_coat": 1}, "lower": {"skirt": 1}, "head": {"hat": 1}, "hair": {"long": 1}},
     [("hat", "long_hair"), ("long_hair", "open_coat")]),
    ({"upper": {"jacket": 1}, "head": {"hat": 1}, "hair": {"volume": 1}}, [("hat", "volume_hair")]),
    ({"upper": {"loose_top": 1}, "head": {"hood": 1}}, [("hood", "loose_top")]),
])
def test_layers_do_not_cross(assets, probs, pairs, pose):
    """The hat encloses the hair, hair and hoods enclose the top's torso: every outer-layer vertex lies
    outside the inner layer (nothing of it farther out, horizontally from the head's axis), the hat's
    crown above the hair's."""
    if pose == "sampled":
        params, _ = sample_pose(np.random.default_rng(5), n_frames=1)
        pose = params["pose"]
    pieces, out, _ = _dressed(assets, probs, pose)
    tab = assets.garment_tables()
    centre = out.joints[0][assets.body.joint_index("head")]
    for outer, inner in pairs:
        o, i = pieces[outer], pieces[inner]
        faces = i.faces if i.source is None or inner.endswith("hair") else i.faces[~tab.arm[i.source[i.faces]].any(1)]
        assert int(_outside_hits(o.verts, i.verts, faces, centre).sum()) == 0, (outer, inner)
    if "hat" in pieces:
        hair = pieces["long_hair" if "long_hair" in pieces else "volume_hair"]
        assert float(pieces["hat"].verts[:, 1].max()) > float(hair.verts[:, 1].max()) + LAYER_GAP


def test_surface_samples_cover_the_faces():
    v = torch.tensor([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    p = surface_samples(v, torch.tensor([[0, 1, 2]]), 4)
    assert p.shape == (15, 3) and (p[:, :2] >= 0).all() and (p[:, :2].sum(1) <= 1 + 1e-6).all()
    assert {tuple(x) for x in v.tolist()} <= {tuple(x) for x in p.tolist()}  # the corners included


@pytest.mark.parametrize("kind", ["loose_top", "jacket", "open_coat"])
def test_upper_shells_keep_to_half_the_room_in_front(assets, kind):
    """Arms beside the torso: a shell vertex moves at most half the way to the next body surface in front
    of its body vertex, so the shells of the arm and the torso facing it do not meet."""
    pieces, out, g = _dressed(assets, {"upper": {kind: 1}}, "arms_down")
    shell = pieces[kind]
    verts, normals = out.verts[0], out.normals[0]
    room = room_in_front(verts, normals, assets.body.faces, shell.source)
    step = (shell.verts - verts[shell.source]).norm(dim=1).double()
    assert (step <= 0.5 * room + 1e-6).all()
    assert int((0.5 * room < g["looseness"]).sum()) > 20  # the rule bites (arms beside the torso)
