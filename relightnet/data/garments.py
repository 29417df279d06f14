"""Clothes and hair as geometry for the generator: what a person wears, and the pieces of one frame.

:func:`sample_garments` draws, per person, one choice in each of four slots (the
probabilities are ``SynthConfig.garment_probs``, merged over :data:`DEFAULT_GARMENT_PROBS`):

- ``upper``: ``none`` (the painted top only), ``loose_top`` (an offset shell of the painted
  top's region, 1–3 cm out, with folds and a gravity sag), ``jacket`` (long sleeves, its own
  colour, to the waist), ``open_coat`` (long sleeves, over the hips, a gap at the front
  through which the painted top shows) or ``dress`` (a skirt surface in the top's colours);
- ``lower``: ``none`` (painted), ``trousers`` (tight: a shell of the leg region 6–12 mm out),
  ``wide_trousers`` (pushed out radially from each leg's hip → ankle axis, widening toward
  the hem) or ``skirt`` (a surface falling from the waist to a hem, not following the legs);
- ``head``: ``none``, ``hat`` (a dome over the skull down to the brow) or ``hood`` (over the
  head, opened at the face, falling onto the shoulders);
- ``hair``: ``painted`` (on the scalp only), ``volume`` (a shell over the scalp, 0.8–3 cm) or
  ``long`` (a volume over the head falling down the back and onto the shoulders, open at the face).

Shells are :func:`relightnet.body.garments.shell_surface` (skinned with the body: each shell
vertex follows a body vertex), hanging surfaces :func:`relightnet.body.garments.ring_surface`
(rebuilt every frame around the pelvis or head joint, so clips move them with the body).
:func:`dress_frame` builds the pieces of one posed frame; :mod:`relightnet.data.clothed`
puts them together with the body into one mesh and one texture.

Layers do not cross (generator version 3): a hat's rings enclose the hair's surface (points
sampled on its faces, :func:`surface_samples`) and rise above its crown, long hair and hoods
enclose the top's torso, each :data:`LAYER_GAP` clear of the layer inside; a top's shell
moves each vertex at most half the room in front of it (:func:`room_in_front`), so the
shells of an arm and of the torso beside it do not meet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from ..body.albedo import REGIONS, region_labels
from ..body.garments import GarmentPiece, RingShape, radial_directions, ring_surface, shell_surface
from ..checks import InputError

__all__ = ["GARMENT_SLOTS", "DEFAULT_GARMENT_PROBS", "GARMENT_TYPES", "garment_probs", "sample_garments",
           "GarmentTables", "garment_tables", "dress_frame", "garment_types", "LAYER_GAP", "room_in_front",
           "surface_samples"]

#: The four slots a person fills and the choices of each (the first: nothing as geometry).
GARMENT_SLOTS = {
    "upper": ("none", "loose_top", "jacket", "open_coat", "dress"),
    "lower": ("none", "trousers", "wide_trousers", "skirt"),
    "head": ("none", "hat", "hood"),
    "hair": ("painted", "volume", "long"),
}
#: Default weights of each slot's choices (``SynthConfig.garment_probs`` overrides slots).
DEFAULT_GARMENT_PROBS = {
    "upper": {"none": 0.25, "loose_top": 0.3, "jacket": 0.17, "open_coat": 0.15, "dress": 0.13},
    "lower": {"none": 0.3, "trousers": 0.3, "wide_trousers": 0.2, "skirt": 0.2},
    "head": {"none": 0.8, "hat": 0.12, "hood": 0.08},
    "hair": {"painted": 0.35, "volume": 0.4, "long": 0.25},
}
#: The geometric garment and hair types a sample can wear (``meta["garments"]["types"]``).
GARMENT_TYPES = ("loose_top", "jacket", "open_coat", "dress", "trousers", "wide_trousers", "skirt", "hat", "hood",
                 "volume_hair", "long_hair")
_ARM_BONES = ("upperarm", "lowerarm", "wrist", "finger", "metacarpal")
_TORSO_BONES = ("root", "spine05", "spine04", "spine03", "spine02", "spine01", "pelvis.L", "pelvis.R")


def garment_probs(overrides: dict | None = None) -> dict:
    """The slot probabilities: ``overrides`` (``{slot: {choice: weight}}``, any subset) replace the
    defaults slot by slot; weights are normalised. Raises InputError on unknown slots or choices."""
    out = {k: dict(v) for k, v in DEFAULT_GARMENT_PROBS.items()}
    if not isinstance(overrides, dict):
        raise InputError(f"garment_probs: expected a mapping of slots, got {type(overrides).__name__}")
    for slot, w in overrides.items():
        if slot not in GARMENT_SLOTS or not isinstance(w, dict) or set(w) - set(GARMENT_SLOTS[slot]) or any(
                isinstance(x, bool) or not isinstance(x, int | float) or not 0 <= x < math.inf for x in w.values()) \
                or not sum(w.values()) > 0:
            raise InputError(f"garment_probs[{slot!r}]: expected a slot of {sorted(GARMENT_SLOTS)} mapping choices "
                             f"of {GARMENT_SLOTS.get(slot, ())} to finite weights >= 0 (not all 0), got {w!r}")
        out[slot] = {c: float(w.get(c, 0.0)) for c in GARMENT_SLOTS[slot]}
    return {s: {c: p / sum(w.values()) for c, p in w.items()} for s, w in out.items()}


def _pick(rng: np.random.Generator, probs: dict) -> str:
    names = list(probs)
    return names[int(rng.choice(len(names), p=np.asarray([probs[n] for n in names])))]


def sample_garments(rng: np.random.Generator, probs: dict, outfit: dict) -> dict:
    """Draw what a person wears as geometry (every draw in a fixed order whatever the outcome).

    Args:
        rng: the sample's garment stream. probs: from :func:`garment_probs`.
        outfit: the painted look (:func:`~relightnet.data.textures.sample_outfit`); its ``sleeves`` and
            ``legs`` are what the body is painted with under the garments (changed here where a garment
            needs it: long legs under trousers, bare legs under skirts and dresses).

    Returns:
        A JSON-serialisable dict: the four slot choices, their parameters (metres, radians) and
        ``outer`` / ``hat`` looks (colour and pattern dicts like the outfit's regions).
    """
    from .textures import _garment_color

    g = {slot: _pick(rng, probs[slot]) for slot in GARMENT_SLOTS}
    if g["upper"] == "dress":
        g["lower"] = "none"
    if g["head"] == "hood" or outfit["hair"] is None:
        g["hair"] = "painted" if outfit["hair"] is not None else "none"
    folds = [[float(rng.integers(5, 15)), float(rng.uniform(0.02, 0.09)), float(rng.uniform(0, 2 * math.pi))]
             for _ in range(3)]
    outer = {**outfit["top"], "color": _garment_color(rng, "top").tolist(), "seed": int(rng.integers(2**31 - 1))}
    outer["color2"] = (np.asarray(outer["color"]) * rng.uniform(0.4, 0.8)).tolist()
    hat = {**outfit["shoes"], "color": _garment_color(rng, "top").tolist(), "pattern": "plain",
           "seed": int(rng.integers(2**31 - 1))}
    g.update({
        "looseness": float(rng.uniform(0.012, 0.03)), "fold_amp": float(rng.uniform(0.003, 0.012)),
        "fold_seed": int(rng.integers(2**31 - 1)), "sag": float(rng.uniform(0.0, 0.03)),
        "coat_gap": float(rng.uniform(0.06, 0.16)), "trouser_offset": float(rng.uniform(0.006, 0.012)),
        "flare": float(rng.uniform(0.03, 0.08)), "skirt_length": float(rng.uniform(0.3, 0.75)),
        "skirt_flare": float(rng.uniform(0.0, 0.15)), "skirt_clearance": float(rng.uniform(0.01, 0.02)),
        "folds": folds, "hair_volume": float(rng.uniform(0.008, 0.03)), "hair_length": float(rng.uniform(0.0, 0.3)),
        "hood_clearance": float(rng.uniform(0.025, 0.045)), "hat_depth": float(rng.uniform(0.02, 0.06)),
        "outer": outer, "hat": hat,
    })
    if g["lower"] in ("trousers", "wide_trousers"):
        outfit["legs"] = "long"
    elif g["lower"] == "skirt" or g["upper"] == "dress":
        outfit["legs"] = "shorts"
    return g


def garment_types(g: dict) -> list[str]:
    """The :data:`GARMENT_TYPES` a drawn ``g`` (:func:`sample_garments`) puts on the body."""
    out = [x for x in (g["upper"], g["lower"], g["head"]) if x in GARMENT_TYPES]
    return out + [f"{g['hair']}_hair"] * (g["hair"] in ("volume", "long"))


@dataclass(frozen=True, eq=False)
class GarmentTables:
    """Per-body-model tables the garments use (:func:`garment_tables`).

    Attributes:
        rest: (V, 3) float32 zero-pose positions. arm: (V,) bool arm and hand vertices.
        head: (V,) bool head vertices (Anny's head part). torso_low: (V,) bool torso below the waist.
        leg_side: (V,) int64 0 left leg, 1 right leg, −1 neither. leg_t: (V,) float32 fraction hip → ankle.
        labels: memo of :func:`relightnet.body.albedo.region_labels` per (sleeves, legs, hair).
        parts: (V,) int64 the body's :func:`~relightnet.body.albedo.anny_part_labels` (region_labels reads them).
    """

    rest: torch.Tensor
    arm: torch.Tensor
    head: torch.Tensor
    torso_low: torch.Tensor
    leg_side: torch.Tensor
    leg_t: torch.Tensor
    labels: dict
    parts: np.ndarray

    def region(self, body, sleeves: str, legs: str, hair: str = "short") -> torch.Tensor:
        key = (sleeves, legs, hair)
        if key not in self.labels:
            self.labels[key] = region_labels(body, sleeves, legs, hair, parts=self.parts)
        return self.labels[key]


def garment_tables(body, parts: np.ndarray, labels: dict | None = None) -> GarmentTables:
    """Build the :class:`GarmentTables` of an Anny body (``parts``: its
    :func:`~relightnet.body.albedo.anny_part_labels`; ``labels``: a region-label memo to share, keyed (sleeves,
    legs, hair))."""
    from ..body.albedo import ANNY_PARTS

    with torch.no_grad():
        out = body()
    rest = out.verts[0].detach().float()
    J = {n: j for n, j in zip(out.joint_names, out.joints[0].detach().double(), strict=True)}
    w = body.anny.vertex_bone_weights.detach().cpu()
    bi = body.anny.vertex_bone_indices.detach().cpu().long()
    names = np.array(body.joint_names)
    dom = names[bi.gather(1, w.argmax(1, keepdim=True))[:, 0].numpy()]
    arm = torch.as_tensor(np.array([any(b in d for b in _ARM_BONES) for d in dom]))
    arm |= torch.as_tensor(np.isin(parts, [ANNY_PARTS.index("hand.L"), ANNY_PARTS.index("hand.R")]))
    head = torch.as_tensor(parts == ANNY_PARTS.index("head"))
    torso_low = torch.as_tensor(np.isin(dom, _TORSO_BONES)) & (rest[:, 1] < float(J["root"][1]) + 0.05)
    side = torch.full((len(rest),), -1, dtype=torch.int64)
    t = torch.zeros(len(rest))
    for k, s in enumerate("LR"):
        leg = torch.as_tensor(np.array([d.endswith(f".{s}") and ("leg" in d or d.startswith("foot")) for d in dom]))
        a, b = J[f"upperleg01.{s}"].float(), J[f"foot.{s}"].float()
        tt = ((rest - a) @ (b - a) / ((b - a) @ (b - a))).clamp(0, 1)
        side[leg] = k
        t[leg] = tt[leg]
    return GarmentTables(rest, arm, head, torso_low, side, t, {} if labels is None else labels, np.asarray(parts))


def _fold_noise(pos: torch.Tensor, seed: int) -> torch.Tensor:
    """(N,) smooth folds in [0, 1] at rest positions (N, 3): a few random plane waves, 8–20 cm long."""
    rng = np.random.default_rng(seed)
    k = rng.normal(size=(4, 3))
    k = k / np.linalg.norm(k, axis=1, keepdims=True) * (2 * np.pi / rng.uniform(0.08, 0.2, (4, 1)))
    ph = rng.uniform(0, 2 * np.pi, 4)
    s = torch.sin(pos.double() @ torch.as_tensor(k.T) + torch.as_tensor(ph)).mean(1)
    return (0.5 + 0.5 * s / 0.7).clamp(0, 1).float()


def _all_in(faces: torch.Tensor, vsel: torch.Tensor) -> torch.Tensor:
    return vsel[faces].all(1)


def room_in_front(verts: torch.Tensor, normals: torch.Tensor, faces: torch.Tensor, idx: torch.Tensor) -> torch.Tensor:
    """(N,) distance (metres) from body vertices ``idx`` (N,) along their normals to the next body surface
    in front (an arm beside the torso, the other arm), inf where the ray escapes. verts, normals: (V, 3);
    faces: (F, 3)."""
    from ..prt import make_engine

    eng = make_engine(verts, faces, threads=1)
    o = verts[idx].double() + 1e-4 * normals[idx].double()
    t = eng.intersect(o.float().numpy(), normals[idx].float().numpy()).t
    return torch.from_numpy(t).double() + 1e-4


#: Gap (metres) between a garment layer and the layer it encloses (hat over hair, hair or hood over a coat).
LAYER_GAP = 0.008


def _upper_shell(kind, g, verts, normals, faces, tab, body, outfit) -> GarmentPiece:
    sleeves = outfit["sleeves"] if kind == "loose_top" else "long"
    lab = tab.region(body, sleeves, outfit["legs"])
    vsel = lab == REGIONS.index("top")
    if kind == "open_coat":
        vsel = vsel | tab.torso_low
    fsel = _all_in(faces, vsel)
    if kind == "open_coat":  # the front gap, on the rest mesh (facing +z)
        c = tab.rest[faces].mean(1)
        fsel &= ~((c[:, 0].abs() < g["coat_gap"] / 2) & (c[:, 2] > 0.0) & ~tab.arm[faces].any(1))
    base = {"loose_top": g["looseness"], "jacket": g["looseness"] + 0.008, "open_coat": g["looseness"] + 0.012}[kind]
    off = base + g["fold_amp"] * _fold_noise(tab.rest, g["fold_seed"])
    # At most half the room in front of each vertex (offset and sag alike), so that the shells of
    # surfaces facing each other (an arm beside the torso) do not meet or cross.
    src = torch.unique(faces[fsel])
    reach = off[src].double() + g["sag"]
    scale = torch.ones(len(verts), dtype=torch.float64)
    scale[src] = (0.5 * room_in_front(verts, normals, faces, src) / reach).clamp(max=1.0)
    return shell_surface(verts, normals, faces, fsel, (off * scale).float(), sag=g["sag"] * scale)


def _lower_shell(kind, g, verts, normals, faces, joints, tab, body, outfit, jidx) -> GarmentPiece:
    lab = tab.region(body, outfit["sleeves"], "long")
    fsel = _all_in(faces, lab == REGIONS.index("bottom"))
    t = tab.leg_t
    off = g["trouser_offset"] + 0.5 * g["fold_amp"] * t * _fold_noise(tab.rest, g["fold_seed"] + 1)
    d = normals.clone()
    if kind == "wide_trousers":
        off = off + g["flare"] * t**1.5
        for k, s in enumerate("LR"):
            leg = tab.leg_side == k
            radial = radial_directions(verts[leg], joints[jidx[f"upperleg01.{s}"]], joints[jidx[f"foot.{s}"]])
            mix = normals[leg] + 2 * t[leg, None] * radial
            d[leg] = mix / mix.norm(dim=1, keepdim=True).clamp_min(1e-9)
    return shell_surface(verts, normals, faces, fsel, off, direction=d)


def _head_frame(verts, joints, tab, jidx):
    head = joints[jidx["head"]]
    eye = (joints[jidx["eye.L"]] + joints[jidx["eye.R"]]) / 2
    front = eye - head
    front[1] = 0.0
    top = float(verts[tab.head][:, 1].max())
    return head, front, top, float(eye[1])


def _open_rows(y_top: float, y_bottom: float, n: int, open_below: float) -> int:
    """The first quad row whose centre lies below ``open_below`` (rings evenly spaced)."""
    step = (y_top - y_bottom) / (n - 1)
    return int(max(0, math.ceil((y_top - open_below) / step - 0.5)))


def dress_frame(g: dict, verts, normals, faces, joints, tab: GarmentTables, body, outfit: dict,
                topo: dict | None = None) -> tuple[list, dict]:
    """The garment pieces of one posed frame.

    Args:
        g: from :func:`sample_garments`. verts, normals: (V, 3) posed body (world frame, y up).
        faces: (F, 3). joints: (J, 3) posed joints. tab: the body's :class:`GarmentTables`.
        body: the AnnyBody (joint names, region labels). outfit: the painted look.
        topo: the topology choices of a clip's first frame (the second result), so that every
            frame has the same faces; None for the first frame.

    Returns:
        ``[(type, GarmentPiece, region id into REGIONS, texture: "body" | "outer" | ring slot), ...]``
        and the topology choices.
    """
    topo = {} if topo is None else topo
    jidx = {n: i for i, n in enumerate(body.joint_names)}
    pieces = []
    if g["upper"] in ("loose_top", "jacket", "open_coat"):
        panel = "body" if g["upper"] == "loose_top" else "outer"
        pieces.append((g["upper"], _upper_shell(g["upper"], g, verts, normals, faces, tab, body, outfit),
                       REGIONS.index("top"), panel))
    if g["lower"] in ("trousers", "wide_trousers"):
        pieces.append((g["lower"], _lower_shell(g["lower"], g, verts, normals, faces, joints, tab, body, outfit, jidx),
                       REGIONS.index("bottom"), "body"))
    not_arm = ~tab.arm
    head, front, top, eye_y = _head_frame(verts, joints, tab, jidx)
    if g["lower"] == "skirt" or g["upper"] == "dress":
        root = joints[jidx["root"]]
        y0 = float(root[1]) + 0.05
        y1 = max(y0 - g["skirt_length"], 0.08)
        n = max(8, int(round(g["skirt_length"] / 0.025)) + 1)
        piece = ring_surface(verts[not_arm], root, front, y0, y1, n, 48, g["skirt_clearance"],
                             shape=RingShape(flare=g["skirt_flare"], folds=tuple(tuple(f) for f in g["folds"])))
        pieces.append(("dress" if g["upper"] == "dress" else "skirt", piece,
                       REGIONS.index("top" if g["upper"] == "dress" else "bottom"), 0))
    coat = None
    if g["upper"] in ("loose_top", "jacket", "open_coat"):  # its torso part, which hair and hoods enclose
        shell = pieces[0][1]
        coat = surface_samples(shell.verts, shell.faces[~tab.arm[shell.source[shell.faces]].any(1)], 2)
    return pieces + _head_pieces(g, verts, normals, faces, tab, body, outfit, topo, (head, front, top, eye_y),
                                 coat), topo


def _around(points: torch.Tensor, centre: torch.Tensor, clearance: float, gap: float) -> torch.Tensor:
    """(N, 3) points moved horizontally toward (or away from) the vertical axis through ``centre`` so
    that a :func:`ring_surface` of ``clearance`` clears the original points by ``gap`` (radius ≥ 0)."""
    rel = points.double() - centre.double()
    rel[:, 1] = 0.0
    r = rel.norm(dim=1, keepdim=True)
    moved = rel * ((r + gap - clearance).clamp_min(0.0) / r.clamp_min(1e-9))
    return (points.double() + moved - rel).to(points.dtype)


def _head_pieces(g, verts, normals, faces, tab, body, outfit, topo, frame, coat) -> list:
    """The hat or hood and the hair of :func:`dress_frame`, layered: the hat encloses the hair, hair
    and hoods enclose the coat's torso (``coat``: (N, 3) or None), each :data:`LAYER_GAP` clear of it."""
    head, front, top, eye_y = frame
    not_arm = ~tab.arm
    out, hair = [], None
    volume = g["hair_volume"] if g["hair"] in ("volume", "long") else 0.0
    if g["hair"] == "volume":
        lab = tab.region(body, outfit["sleeves"], outfit["legs"])
        fsel = _all_in(faces, lab == REGIONS.index("hair"))
        off = g["hair_volume"] * (0.6 + 0.4 * _fold_noise(tab.rest * 3, g["fold_seed"] + 2))
        hair = ("volume_hair", shell_surface(verts, normals, faces, fsel, off), REGIONS.index("hair"), "body")
    elif g["hair"] == "long":
        pts = _enclosing(verts[not_arm & (verts[:, 1] > eye_y - 0.6)], coat, head, volume)
        y1 = eye_y - 0.2 - g["hair_length"]
        rows = topo.setdefault("hair_rows", _open_rows(top + volume, y1, 14, eye_y + 0.05))
        piece = ring_surface(pts, head, front, top + volume, y1, 14, 48, volume,
                             shape=RingShape(min_radius=0.03, open_rows=rows, open_halfwidth=math.radians(80),
                                             cap=True))
        hair = ("long_hair", piece, REGIONS.index("hair"), 2)
    if g["head"] == "hat":
        y1, y0 = eye_y + g["hat_depth"], top + volume + 0.012
        inner = None if hair is None else surface_samples(hair[1].verts, hair[1].faces, 4)
        if inner is not None:  # above the hair's crown too
            y0 = max(y0, float(inner[:, 1].max()) + LAYER_GAP)
        pts = _enclosing(verts[tab.head], inner, head, volume + 0.012)
        piece = ring_surface(pts, head, front, y0, y1, 10, 40, volume + 0.012,
                             shape=RingShape(min_radius=0.03, cap=True))
        out.append(("hat", piece, REGIONS.index("hair"), 1))
    elif g["head"] == "hood":
        c = g["hood_clearance"]
        pts = _enclosing(verts[not_arm & (verts[:, 1] > eye_y - 0.45)], coat, head, c)
        rows = topo.setdefault("hood_rows", _open_rows(top + c, eye_y - 0.3, 16, eye_y + 0.07))
        piece = ring_surface(pts, head, front, top + c, eye_y - 0.3, 16, 48, c,
                             shape=RingShape(min_radius=0.03, open_rows=rows, open_halfwidth=math.radians(60),
                                             cap=True))
        out.append(("hood", piece, REGIONS.index("top"), 1))
    return out + ([hair] if hair is not None else [])


def surface_samples(verts: torch.Tensor, faces: torch.Tensor, n: int) -> torch.Tensor:
    """(F·(n+1)(n+2)/2, 3) points on the faces (F, 3) of a mesh with vertices (V, 3): a barycentric grid of
    step 1/n on each face (its corners included), so that a surface enclosing them encloses the faces."""
    i, j = torch.meshgrid(torch.arange(n + 1), torch.arange(n + 1), indexing="ij")
    keep = (i + j) <= n
    b = torch.stack([i[keep], j[keep], n - i[keep] - j[keep]], 1).to(verts.dtype) / n  # (P, 3)
    return torch.einsum("pk,fkc->fpc", b, verts[faces]).reshape(-1, 3)


def _enclosing(body_pts: torch.Tensor, inner: torch.Tensor | None, centre: torch.Tensor, clearance: float):
    """The points a ring surface of ``clearance`` must enclose: the body's, and an inner layer's (N, 3) moved
    so that it is cleared by :data:`LAYER_GAP`."""
    if inner is None:
        return body_pts
    return torch.cat([body_pts, _around(inner, centre, clearance, LAYER_GAP).to(body_pts.dtype)])
