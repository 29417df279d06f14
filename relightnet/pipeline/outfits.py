"""The dressed avatar: the generator's clothes and hair, as geometry, skinned to the avatar's body.

An outfit is ``NAME`` (one of :data:`relightnet.names.OUTFITS`) or ``random:SEED``:

- a named outfit fixes what is worn in each of the generator's garment slots
  (:data:`relightnet.data.garments.GARMENT_SLOTS`) and a seed for its look (colours and
  patterns, :func:`relightnet.data.textures.sample_outfit`);
- ``random:SEED`` draws the slots with the generator's probabilities and the look, from SEED.

:class:`DressedBody` wraps the avatar's :class:`~relightnet.body.AnnyBody`: calling it poses
the body and dresses every frame (:func:`relightnet.data.garments.dress_frame`: shells follow
their body vertices, hanging surfaces are rebuilt around the pelvis or head joint), so the
renderer sees one mesh — body first, then the garment pieces — with the topology of the first
frame in every frame. Its :attr:`DressedBody.albedo` is the generator's texture of the outfit
(:func:`relightnet.data.clothed.clothed_mesh`: the painted body plus garment panels). The PRT
is that of the whole mesh, so cloth shadows the body and the body the cloth. Anything that
renders a body model (:func:`relightnet.render.jobs.render_body_frames`, the avatar job,
``render-body``) takes a DressedBody in its place.

Two things the generator's clothes lack are added (:mod:`.outfit_parts`): the shells' hems are cut
along smooth lines through triangles instead of following the body's face edges, and every outfit
wears shoes (:data:`OUTFIT_SHOES`; ``random:SEED`` draws a kind) — closed shells around the feet that
pose with the foot, toe and lower-leg bones, with their own panel in the texture and the same PRT.
The dressed mesh's vertices are the clothed mesh's, then the hems' new ones, then the shoes'.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch

from ..body.base import BodyOutput
from ..body.shoes import SHOE_KINDS
from ..checks import InputError
from ..names import OUTFITS
from .outfit_parts import hem_cut, shoe_panel, shoe_rig

__all__ = ["OUTFITS", "OUTFIT_SLOTS", "OUTFIT_SHOES", "OUTFIT_COLORS", "OutfitDraw", "draw_outfit", "DressedBody",
           "dressed_body", "outfit_field", "avatar_look", "captured_body"]

#: What each named outfit wears (upper, lower, head, hair) and the seed of its look.
OUTFIT_SLOTS = {
    "casual": (("loose_top", "trousers", "none", "volume"), 11),
    "dress": (("dress", "none", "none", "long"), 12),
    "jacket": (("jacket", "wide_trousers", "none", "volume"), 13),
    "coat": (("open_coat", "trousers", "hat", "volume"), 14),
    "skirt": (("loose_top", "skirt", "none", "long"), 15),
    "hood": (("jacket", "trousers", "hood", "painted"), 16),
}
#: The shoes each named outfit wears (:data:`relightnet.body.shoes.SHOE_KINDS`; ``random:SEED`` draws one).
OUTFIT_SHOES = {"casual": "sneaker", "dress": "flat", "jacket": "dress_shoe", "coat": "boot", "skirt": "boot",
                "hood": "sneaker"}

#: sRGB colours of the named outfits' pieces (plain fabric; the rest of the look is drawn from the seed).
OUTFIT_COLORS = {
    "casual": {"top": (0.86, 0.85, 0.8), "bottom": (0.25, 0.33, 0.5), "shoes": (0.12, 0.12, 0.13)},
    "dress": {"top": (0.5, 0.13, 0.18), "shoes": (0.1, 0.08, 0.08)},
    "jacket": {"outer": (0.14, 0.17, 0.3), "top": (0.85, 0.85, 0.85), "bottom": (0.72, 0.64, 0.48),
               "shoes": (0.3, 0.2, 0.13)},
    "coat": {"outer": (0.62, 0.47, 0.32), "top": (0.92, 0.88, 0.8), "bottom": (0.2, 0.2, 0.22),
             "shoes": (0.1, 0.1, 0.1), "hat": (0.25, 0.22, 0.2)},
    "skirt": {"top": (0.92, 0.88, 0.8), "bottom": (0.38, 0.4, 0.25), "shoes": (0.4, 0.28, 0.2)},
    "hood": {"outer": (0.45, 0.45, 0.47), "bottom": (0.25, 0.33, 0.5), "shoes": (0.85, 0.85, 0.85)},
}


def _paint_named(name: str, look: dict, g: dict) -> None:
    """Give a named outfit's pieces their plain colours (:data:`OUTFIT_COLORS`), in place."""
    from ..color import srgb_to_linear_np

    for part, srgb in OUTFIT_COLORS[name].items():
        d = g[part] if part in ("outer", "hat") else look[part]
        c = srgb_to_linear_np(np.asarray(srgb, dtype=np.float64))
        d.update(color=c.tolist(), color2=(c * 0.75).tolist(), pattern="plain")


@dataclass(frozen=True)
class OutfitDraw:
    """An outfit: ``look`` (the painted look, :func:`~relightnet.data.textures.sample_outfit`),
    ``garments`` (:func:`~relightnet.data.garments.sample_garments`), both JSON-serialisable, and the
    ``shoes`` kind (:data:`~relightnet.body.shoes.SHOE_KINDS`); ``spec`` as given."""

    spec: str
    look: dict
    garments: dict
    shoes: str = field(default="sneaker")


def draw_outfit(spec: str) -> OutfitDraw:
    """Parse ``NAME`` or ``random:SEED`` and draw the outfit (deterministic for a spec)."""
    from ..data.garments import GARMENT_SLOTS, garment_probs, sample_garments
    from ..data.textures import sample_outfit

    spec = str(spec)
    if spec.startswith("random:"):
        try:
            seed = int(spec[7:])
        except ValueError:
            raise InputError(f"--outfit {spec}: expected random:SEED with an integer SEED") from None
        if seed < 0:
            raise InputError(f"--outfit {spec}: the seed must be >= 0")
        probs = garment_probs({})
    elif spec in OUTFIT_SLOTS:
        slots, seed = OUTFIT_SLOTS[spec]
        probs = garment_probs({s: {c: 1.0} for s, c in zip(GARMENT_SLOTS, slots, strict=True)})
    else:
        raise InputError(f"--outfit {spec}: expected one of {', '.join(OUTFITS)} or random:SEED")
    rng = np.random.default_rng([seed, 28])
    look = sample_outfit(rng)
    if spec in OUTFIT_SLOTS and look["hair"] is None:  # a named outfit's hair is worn: not bald
        look["hair"] = [0.05, 0.03, 0.02]
    g = sample_garments(rng, probs, look)
    if spec in OUTFIT_SLOTS:
        _paint_named(spec, look, g)
        shoes = OUTFIT_SHOES[spec]
    else:  # a stream of its own, so the look and garments are those the seed always drew
        shoes = str(np.random.default_rng([seed, 28, 5]).choice(sorted(SHOE_KINDS)))
    return OutfitDraw(spec, look, g, shoes)


class DressedBody:
    """An Anny body wearing an outfit (module docstring); call it like the body model. ``hems=False`` keeps the
    generator's face-wise garment borders (for comparison) instead of cutting them smooth; ``subdivide=True``
    splits the cloth's outer sides once as the generator does for its ground truth (4× the cloth's faces; the
    avatar job keeps them as built: it ray casts every vertex of every frame).

    Attributes:
        body: the wrapped :class:`~relightnet.body.AnnyBody`. outfit: the :class:`OutfitDraw`.
        faces: (F', 3) the dressed mesh's faces (body faces first). albedo: the outfit's
            :class:`~relightnet.render.TexturedAlbedo`. types: the garment types worn, then ``"shoes"``.
        face_piece: (F',) int64 the index into ``types`` of each face's piece, −1 for the body.
        cut: the :class:`~.outfit_parts.HemCut` of the garments' hems. shoes: the :class:`~.outfit_parts.ShoeRig`.
        n_body_verts: V, the body's vertex count (its vertices come first).
    """

    def __init__(self, body, outfit: OutfitDraw, hems: bool = True, subdivide: bool = False) -> None:
        from ..body import AnnyBody
        from ..data.clothed import clothed_mesh
        from ..data.sample import prepare_assets
        from ..data.textures import paint_albedo, uv_atlas
        from ..render.frame import TexturedAlbedo

        if not isinstance(body, AnnyBody):
            raise InputError(f"--outfit: outfits dress the Anny body, not {type(body).__name__}")
        self.body, self.outfit = body, outfit
        assets = prepare_assets(body)
        look = outfit.look
        self._field = outfit_field(body, look, assets)
        self._tab = assets.garment_tables()
        atlas = uv_atlas(body, 1024)
        tex = paint_albedo(atlas, self._field, look)
        with torch.no_grad():
            rest = body()
        self._topo = None
        pieces = self._pieces(rest.verts[0], rest.normals[0], rest.joints[0])
        m = clothed_mesh(outfit.garments, look, rest.verts.detach(), rest.normals.detach(), rest.joints.detach(),
                         body, self._tab, tex, self._field, atlas, subdivide)
        n_pieces = sum(len(p[1].verts) for p in pieces)
        self._edges = m.midpoints[:, 1:]  # the subdivided outer sides' midpoints follow every frame's pieces
        self._mid = m.midpoints
        self._inner = self._thickness(m, pieces, n_pieces)
        self._rest = rest.verts[0].detach()
        self.cut = hem_cut(m.faces, m.verts[0], m.uv, m.uv_faces, self._shell_ranges(pieces) if hems else [],
                           m.midpoints)
        self.shoes = shoe_rig(body, self._rest, rest.joints[0].detach(), outfit.shoes)
        n_cut = m.verts.shape[1] + len(self.cut.edges)
        self.faces = torch.cat([self.cut.faces, self.shoes.faces + n_cut])
        self.types, self.n_body_verts = [*m.types, "shoes"], body.num_verts
        tex, uv = self._with_shoe_panel(m.tex, self.cut.uv, outfit)
        self.uv = uv
        self.uv_faces = torch.cat([self.cut.uv_faces, self.shoes.faces + len(self.cut.uv)])
        self.albedo = TexturedAlbedo(tex, self.uv, self.uv_faces)
        self.face_piece = self._face_pieces(pieces, m.verts.shape[1])

    def _face_pieces(self, pieces: list, n_clothed: int) -> torch.Tensor:
        """(F',) the piece of every face: −1 the body, k the k-th of :attr:`types` (the shoes last)."""
        vp = torch.full((n_clothed,), -1, dtype=torch.int64)
        start = self.body.num_verts
        for k, p in enumerate(pieces):
            n = len(p[1].verts) * (1 if self._inner is None else 2)
            vp[start:start + n] = k
            start += n
        vp[self._mid[:, 0]] = vp[self._mid[:, 1]]
        vp = torch.cat([vp, vp[self.cut.edges[:, 0]], torch.full((len(self.shoes.rest),), len(pieces))])
        return vp[self.faces[:, 0]]

    def _shell_ranges(self, pieces: list) -> list:
        """(first vertex, count, reach) in the clothed mesh of every piece whose hems are cut (with its inner
        side): the shells, whose borders follow the body's face edges (reach 5: the hem about 2.5 edges in),
        and the face openings of hoods and long hair, whose corners are rounded (reach 1.2)."""
        out, start = [], self.body.num_verts
        for p in pieces:
            n = len(p[1].verts) * (1 if self._inner is None else 2)
            if p[1].source is not None:
                out.append((start, n, 5.0))
            elif p[0] in ("hood", "long_hair"):
                out.append((start, n, 1.2))
            start += n
        return out

    def _with_shoe_panel(self, tex: torch.Tensor, uv: torch.Tensor, outfit: OutfitDraw) -> tuple:
        """The texture with the shoe panel appended on the right, (the UVs moved into it, then the shoes')."""
        S, P = tex.shape[0], tex.shape[1] // tex.shape[0]
        panel = shoe_panel(S, outfit.shoes, outfit.look["shoes"]["color"])
        moved = torch.stack([uv[:, 0] * P / (P + 1), uv[:, 1]], 1)
        su = self.shoes.uv
        shoe_uv = torch.stack([(P + 0.002 + 0.996 * su[:, 0]) / (P + 1), su[:, 1]], 1)
        return torch.cat([tex, panel], 1).contiguous(), torch.cat([moved, shoe_uv]).float()

    def _thickness(self, m, pieces: list, n_pieces: int) -> float | None:
        """How the clothed mesh lays out each piece: its vertices alone (None), or followed by an inner side
        moved this far against the normals (two-sided cloth); read off the rest frame."""
        V, nv = self.body.num_verts, m.verts.shape[1] - len(m.midpoints)
        if nv == V + n_pieces:
            return None
        if nv != V + 2 * n_pieces:
            raise InputError("--outfit: the garment pieces disagree with the clothed mesh (a bug)")
        p = pieces[0][1]
        return float((m.verts[0, V:V + len(p.verts)] - m.verts[0, V + len(p.verts):V + 2 * len(p.verts)]).norm(dim=1)
                     .median())

    def _piece_arrays(self, piece) -> tuple[torch.Tensor, torch.Tensor]:
        """One piece's (verts, normals) as the clothed mesh lays them out (:meth:`_thickness`)."""
        if self._inner is None:
            return piece.verts, piece.normals
        return (torch.cat([piece.verts, piece.verts - self._inner * piece.normals]),
                torch.cat([piece.normals, -piece.normals]))

    @property
    def num_verts(self) -> int:
        """V', the dressed mesh's vertex count."""
        return int(self.faces.max()) + 1

    def _pieces(self, verts, normals, joints) -> list:
        from ..data.garments import dress_frame

        pieces, self._topo = dress_frame(self.outfit.garments, verts, normals, self.body.faces, joints, self._tab,
                                         self.body, self.outfit.look, self._topo)
        return pieces

    def __call__(self, params=None, **kwargs) -> BodyOutput:
        """Pose the body (arguments as the body model's) and dress each frame: a :class:`BodyOutput` of
        the dressed mesh (verts, normals (B, V', 3); faces (F', 3); joints of the body)."""
        from ..body.subdivide import midpoint_values

        with torch.no_grad():
            out = self.body(params, **kwargs)
        shoe_v, shoe_n = self.shoes.pose(self._rest, out.verts.detach())
        vs, ns = [], []
        for b in range(out.batch_size):
            arrays = [self._piece_arrays(p[1]) for p in self._pieces(out.verts[b], out.normals[b], out.joints[b])]
            v = midpoint_values(torch.cat([out.verts[b], *[a[0] for a in arrays]]), self._edges)
            n = midpoint_values(torch.cat([out.normals[b], *[a[1] for a in arrays]]), self._edges, unit=True)
            v, n = self.cut.apply(v, n)
            vs.append(torch.cat([v, shoe_v[b]]))
            ns.append(torch.cat([n, shoe_n[b]]))
        return BodyOutput(torch.stack(vs).float(), self.faces, self.uv, self.uv_faces, torch.stack(ns).float(),
                          out.joints, out.joint_names)


def outfit_field(body, look: dict, assets=None) -> np.ndarray:
    """(V, R) the region field an outfit's body is painted through: the look's region labels with the feet
    (under the shoes) given to the legs' region — the trousers' colour under long legs, else skin — so no
    painted shoe edge shows above a shoe, blurred over 16 steps (about four vertex rings, as the default
    albedo, :mod:`.smooth_albedo`) and painted on a 1024² atlas, so painted edges (a dress's neckline,
    bare arms) are as smooth as the hems. ``assets``: the body's :class:`~relightnet.data.sample.SynthAssets`."""
    from ..body.albedo import REGIONS
    from ..data.sample import prepare_assets
    from ..data.textures import region_field

    assets = prepare_assets(body) if assets is None else assets
    ids = assets.region_labels(look["sleeves"], look["legs"], "none" if look["hair"] is None else "short").clone()
    ids[ids == REGIONS.index("shoes")] = REGIONS.index("bottom" if look["legs"] == "long" else "skin")
    return region_field(body.faces.cpu().numpy(), ids.numpy(), iters=16)


def avatar_look(body, albedo="default", outfit: str | None = None, captured=None) -> tuple:
    """The avatar job's body and albedo: (``body``, the body to render, its albedo). With an ``outfit``
    (``NAME`` or ``random:SEED``) the body to render is a :class:`DressedBody` with the outfit's albedo; with
    ``captured`` (an avatar file from ``relightnet capture``) a :class:`~relightnet.capture.CapturedBody` with
    the captured texture; either way ``albedo`` must be ``"default"``. Without, ``body`` and
    :func:`~relightnet.pipeline.scene.avatar_albedo`."""
    from .scene import avatar_albedo

    if outfit is None and captured is None:
        return body, body, avatar_albedo(body, albedo)
    if outfit is not None and captured is not None:
        raise InputError("--avatar brings its own geometry and texture: drop --outfit")
    if not (isinstance(albedo, str) and albedo == "default"):
        raise InputError(f"{'--outfit' if outfit else '--avatar'} brings its own albedo: drop --albedo")
    dressed = dressed_body(body, outfit) if outfit is not None else captured_body(body, captured)
    return body, dressed, dressed.albedo


def captured_body(body, path) -> object:
    """A :class:`~relightnet.capture.CapturedBody` of the avatar file at ``path`` on ``body`` (Anny)."""
    from ..body import AnnyBody
    from ..capture import CapturedBody, load_avatar

    if not isinstance(body, AnnyBody):
        raise InputError(f"--avatar: a captured person is an Anny body, not {type(body).__name__}")
    return CapturedBody(body, load_avatar(path, body.num_verts))


def dressed_body(body, outfit: str | None) -> object:
    """``body`` itself when ``outfit`` is None, else a :class:`DressedBody` wearing ``draw_outfit(outfit)``."""
    return body if outfit is None else DressedBody(body, draw_outfit(outfit))
