"""The clothed person as one mesh: the body plus its garment pieces, one texture, one region field.

:func:`clothed_mesh` puts the pieces of every frame (:func:`relightnet.data.garments.dress_frame`)
after the body's vertices and faces, so the PRT, the rasterizer and the maps see one mesh —
what the image shows, with occlusion and interreflection between body and cloth.

Texture: P panels side by side, each S × S, (S, P·S, 3): panel 0 is the body's painted
atlas (shells that copy the painted region, like a loose top, trousers or volume hair,
reuse the body's UVs there); an ``outer`` panel (jackets, coats) paints the whole atlas in
the outer garment's look and those shells use the body's UVs shifted into it; a ``rings``
panel holds the hanging surfaces in three rows (0: skirt or dress, 1: hat or hood, 2: long
hair), each texel painted at a nominal cylinder point (u around, v down) so that the
generator's solid patterns continue around them.

Every piece is two-sided (:data:`THICKNESS`): an inner copy faces the body, so looking into
a sleeve, under a skirt or into a hood shows a surface facing the camera with its own PRT.

Every piece's outer side is subdivided once (:func:`relightnet.body.subdivide.subdivide_faces`): its vertices
are twice as dense, so the per-vertex transport follows shadows between garment layers more
closely; the PRT ray casts the new midpoint vertices only at shadow edges
(:func:`relightnet.prt.refined_transport`, with ``ClothedMesh.midpoints``).

Covered faces: body faces under a shell (its copied faces, less two rings of vertices at
its edges, where the body shows through openings by design) or inside a skirt between
waist and hem. A pixel that shows one is body showing through cloth;
``hidden_body_share`` is their share of the pixels showing a garment or a covered face.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ..body.albedo import REGIONS
from ..body.garments import GarmentPiece
from ..body.subdivide import midpoint_values, subdivide_faces
from .garments import GarmentTables, dress_frame
from .textures import ALBEDO_MAX, ALBEDO_MIN, garment_texels, hair_texels

__all__ = ["ClothedMesh", "clothed_mesh", "hidden_body_share"]

_SLOTS = 3
_NOMINAL = {0: (0.18, 1.0, 0.7), 1: (0.11, 1.75, 0.5), 2: (0.11, 1.75, 0.6)}  # radius, top y, height (metres)


@dataclass(frozen=True, eq=False)
class ClothedMesh:
    """A body with its garments, every frame (see module docstring).

    Attributes:
        verts, normals: (T, V', 3) float32, the body's V vertices first.
        faces: (F', 3) int64, the body's F faces first. uv: (Vt', 2) float32. uv_faces: (F', 3) int64.
        tex: (S, P·S, 3) float32 linear albedo. field: (V', R) float32 region field (parts map).
        covered: (F',) bool body faces hidden under garments. hidden: (V',) bool vertices all of
            whose faces are covered (their transport is never seen). n_body_faces: F.
        types: the garment types worn (:data:`~relightnet.data.garments.GARMENT_TYPES`).
        midpoints: (M, 3) int64 rows (vertex, endpoint a, endpoint b) of the vertices added by
            subdividing the garments' outer sides (the last M vertices).
    """

    verts: torch.Tensor
    normals: torch.Tensor
    faces: torch.Tensor
    uv: torch.Tensor
    uv_faces: torch.Tensor
    tex: torch.Tensor
    field: np.ndarray
    covered: torch.Tensor
    hidden: torch.Tensor
    n_body_faces: int
    types: list
    midpoints: torch.Tensor


#: Cloth thickness (metres): every piece gets an inner side this far in, facing the body.
THICKNESS = 0.002


def _two_sided(piece: GarmentPiece) -> GarmentPiece:
    """The piece with an inner side: its vertices moved ``THICKNESS`` against the normals, normals
    flipped, faces wound the other way (so a look into a sleeve, a skirt or a hood sees a surface
    facing it, shaded with its own transport). Source faces and UVs are repeated."""
    nv = len(piece.verts)
    return GarmentPiece(
        torch.cat([piece.verts, piece.verts - THICKNESS * piece.normals]), torch.cat([piece.normals, -piece.normals]),
        torch.cat([piece.faces, piece.faces[:, [0, 2, 1]] + nv]),
        None if piece.source is None else torch.cat([piece.source, piece.source]),
        None if piece.source_faces is None else torch.cat([piece.source_faces, piece.source_faces]),
        None if piece.uv is None else torch.cat([piece.uv, piece.uv]))


def _uv_faces(piece: GarmentPiece, uv_faces: torch.Tensor) -> torch.Tensor:
    """(Fg, 3) UV faces of a two-sided shell: its source faces' UVs, the inner half wound like its faces."""
    f = uv_faces[piece.source_faces]
    half = len(f) // 2
    return torch.cat([f[:half], f[half:][:, [0, 2, 1]]])


def _erode(faces: torch.Tensor, fsel: torch.Tensor, n_verts: int, rings: int = 2) -> torch.Tensor:
    """(F,) the selected faces none of whose vertices lie within ``rings`` edges of the selection's border."""
    inside = torch.zeros(n_verts, dtype=torch.bool)
    inside[faces[fsel].flatten()] = True
    bad = torch.zeros(n_verts, dtype=torch.bool)
    bad[faces[~fsel].flatten()] = True
    bad &= inside
    for _ in range(rings):
        bad[faces[bad[faces].any(1)].flatten()] = True
    return fsel & ~bad[faces].any(1)


def _ring_panel(S: int, slots: dict, outfit: dict, g: dict) -> torch.Tensor:
    """(S, S, 3) the rings panel: each used slot row painted at nominal cylinder points."""
    out = torch.full((S, S, 3), 0.5)
    h = S // _SLOTS
    for slot, kind in slots.items():
        r0, y0, span = _NOMINAL[slot]
        u = (torch.arange(S) + 0.5) / S
        v = (torch.arange(h) + 0.5) / h  # row 0 = top of the slot = v_local 1
        th = 2 * np.pi * u
        pos = torch.stack(torch.broadcast_tensors(r0 * torch.cos(th)[None], (y0 - v * span)[:, None],
                                                  r0 * torch.sin(th)[None]), -1).reshape(-1, 3).float()
        if kind == "long_hair":
            col = hair_texels(outfit["hair"], pos, np.random.default_rng(g["fold_seed"]))
        else:
            look = {"skirt": outfit["bottom"], "dress": outfit["top"], "hat": g["hat"],
                    "hood": g["outer"] if g["upper"] in ("jacket", "open_coat") else outfit["top"]}[kind]
            col = garment_texels(look, pos)
        out[slot * h:(slot + 1) * h] = col.reshape(h, S, 3)
    return out


def _panel_uv(uv: torch.Tensor, panel: int, n_panels: int, slot: int | None = None, S: int = 512) -> torch.Tensor:
    """Map (Vt, 2) UVs in [0, 1]² into a panel (and a slot row of the rings panel, with a 2-texel margin)."""
    u, v = uv[:, 0], uv[:, 1]
    if slot is not None:
        m = 2.0 / S
        h = 1.0 / _SLOTS
        u = m + u * (1 - 2 * m)
        v = 1 - (slot + 1) * h + m + v * (h - 2 * m)
    return torch.stack([(panel + u) / n_panels, v], 1)


def clothed_mesh(g: dict, outfit: dict, verts: torch.Tensor, normals: torch.Tensor, joints: torch.Tensor, body,
                 tab: GarmentTables, body_tex: torch.Tensor, field: np.ndarray, atlas,
                 subdivide: bool = True) -> ClothedMesh:
    """Dress every frame of a posed body and put body and garments into one mesh and texture.

    Args:
        g: :func:`~relightnet.data.garments.sample_garments`. outfit: the painted look.
        verts, normals: (T, V, 3) posed body (world frame). joints: (T, J, 3).
        body: the AnnyBody. tab: its :class:`~relightnet.data.garments.GarmentTables`.
        body_tex: (S, S, 3) the painted body texture. field: (V, R) the body's region field.
        atlas: the body's :class:`~relightnet.data.textures.UVAtlas` (texel positions).
        subdivide: split the garments' outer sides once (the generator's ground truth); False keeps
            them as built (no midpoints: a quarter of the cloth's faces, for a renderer that needs speed).

    Returns:
        :class:`ClothedMesh`.
    """
    faces = body.faces
    T, V = verts.shape[:2]
    frames, topo = [], None
    for t in range(T):
        pieces, topo = dress_frame(g, verts[t], normals[t], faces, joints[t], tab, body, outfit, topo)
        frames.append([(k, _two_sided(p), r, w) for k, p, r, w in pieces])
    S = body_tex.shape[0]
    outer = any(p[3] == "outer" for p in frames[0])
    slots = {p[3]: p[0] for p in frames[0] if isinstance(p[3], int)}
    n_panels = 1 + outer + bool(slots)
    panels = [body_tex]
    if outer:
        pos = torch.from_numpy(atlas.texel_pos)
        col = garment_texels(g["outer"], pos, torch.from_numpy(atlas.texel_source))
        panels.append(col.clamp(ALBEDO_MIN, ALBEDO_MAX).reshape(S, S, 3))
    if slots:
        panels.append(_ring_panel(S, slots, outfit, g).clamp(ALBEDO_MIN, ALBEDO_MAX))
    tex = torch.cat(panels, 1).contiguous()
    body_uv = body.uv.detach().float()
    uvs = [_panel_uv(body_uv, 0, n_panels)]
    if outer:
        uvs.append(_panel_uv(body_uv, 1, n_panels))
    uv_faces, fcs, fields, outer_f = [body.uv_faces], [faces], [field], [torch.zeros(faces.shape[0], dtype=torch.bool)]
    covered = torch.zeros(faces.shape[0], dtype=torch.bool)
    nv, nuv = V, sum(len(u) for u in uvs)
    for _kind, piece, region, where in frames[0]:
        fcs.append(piece.faces + nv)
        half = piece.faces.shape[0] // 2  # two-sided: the outer side's faces come first
        outer_f.append(torch.arange(piece.faces.shape[0]) < half)
        if piece.source is not None:
            uv_faces.append(_uv_faces(piece, body.uv_faces) + (len(body_uv) if where == "outer" else 0))
            sel = torch.zeros(faces.shape[0], dtype=torch.bool)
            sel[piece.source_faces] = True
            covered |= _erode(faces, sel, V)
        else:
            uvs.append(_panel_uv(piece.uv, n_panels - 1, n_panels, where, S))
            uv_faces.append(piece.faces + nuv)
            nuv += len(piece.uv)
        fields.append(np.eye(len(REGIONS), dtype=np.float32)[np.full(len(piece.verts), region)])
        nv += len(piece.verts)
    if g["lower"] == "skirt" or g["upper"] == "dress":
        y = tab.rest[faces][..., 1]
        top = float(tab.rest[tab.torso_low][:, 1].max())
        inside = (y < top - 0.03).all(1) & (y > top - g["skirt_length"] + 0.08).all(1) & ~tab.arm[faces].any(1)
        covered |= inside
    all_v = torch.cat([verts, *[torch.stack([f[i][1].verts for f in frames]) for i in range(len(frames[0]))]], 1)
    all_n = torch.cat([normals, *[torch.stack([f[i][1].normals for f in frames]) for i in range(len(frames[0]))]], 1)
    faces_all = torch.cat(fcs)
    cov = torch.cat([covered, torch.zeros(faces_all.shape[0] - faces.shape[0], dtype=torch.bool)])
    outer_f = torch.cat(outer_f) & subdivide
    sub = subdivide_faces(faces_all, all_v.shape[1], outer_f)
    uv_all = torch.cat(uvs).float()
    sub_uv = subdivide_faces(torch.cat(uv_faces), len(uv_all), outer_f)
    faces_all, cov = sub.faces, cov[sub.parent]
    all_v, all_n = midpoint_values(all_v.float(), sub.edges), midpoint_values(all_n.float(), sub.edges, unit=True)
    regions = midpoint_values(torch.from_numpy(np.concatenate(fields)), sub.edges).numpy()
    seen = torch.zeros(all_v.shape[1], dtype=torch.bool)
    seen[faces_all[~cov].flatten()] = True
    return ClothedMesh(all_v, all_n, faces_all, midpoint_values(uv_all, sub_uv.edges), sub_uv.faces, tex,
                       regions, cov, ~seen, int(faces.shape[0]), [p[0] for p in frames[0]], sub.midpoints)


def hidden_body_share(pix_face: torch.Tensor, covered: torch.Tensor, n_body_faces: int) -> float:
    """Share of the pixels showing a garment or a covered body face that show the covered body face
    (body through cloth); 0 when neither is seen. ``pix_face``: (N,) the face of each covered pixel."""
    through = int(covered[pix_face].sum())
    cloth = int((pix_face >= n_body_faces).sum())
    return through / max(through + cloth, 1)
