"""Random albedo textures for Anny: skin, hair, clothes with patterns, painted in UV space.

The texture lives in Anny's UV layout (row 0 = v = 1, as :mod:`relightnet.raster.texture`).
:func:`uv_atlas` rasterizes the UV triangles once per body model: every texel gets the
triangle covering it and its barycentrics (texels outside the UV islands copy the nearest
island texel, which pads the islands for bilinear lookups), hence

- ``texel_vertex``: the nearest mesh vertex (largest barycentric);
- ``texel_tri`` / ``texel_bary``: the triangle's three vertices and the barycentrics, to
  interpolate per-vertex fields. Region labels are per vertex, and a nearest-vertex
  assignment gives saw-tooth garment edges; :func:`region_field` smooths the one-hot
  labels over the mesh (a few Jacobi steps of the graph Laplacian) and a texel (or pixel)
  takes the arg-max of the field interpolated at its barycentrics, so edges follow smooth
  iso-lines through the triangles;
- ``texel_pos``: its position on the zero-pose, default-phenotype mesh (metres, y up,
  facing +z). Patterns are evaluated at these 3D points ("solid" texturing painted into
  the UV texture), so stripes run around the body and continue across UV seams instead
  of following the arbitrary orientation of each UV island.

Garments (:func:`sample_outfit`): per region a base colour (neutrals, typical garment
colours, or any hue) and a pattern — plain, stripes (any direction, 1–10 cm period),
checks (two stripe sets), noise (heather / mottled / camouflage-like smooth 3D noise),
blobs (polka dots or large print-like shapes) — times a fabric-like low-frequency
variation and a fine grain. Skin: :func:`relightnet.body.albedo.skin_color` of a random tone with
a per-channel jitter and slight mottling; hair from a natural palette with streaky grain;
eyes and mouth as in :func:`relightnet.body.default_albedo`. All values lie in
[:data:`ALBEDO_MIN`, :data:`ALBEDO_MAX`].
"""

from __future__ import annotations

import colorsys
import math
from dataclasses import dataclass

import numpy as np
import torch

from ..body.albedo import ANNY_PARTS, REGIONS, anny_part_labels, skin_color
from ..checks import InputError
from ..color import srgb_to_linear_np
from ..raster import rasterize

__all__ = ["ALBEDO_MIN", "ALBEDO_MAX", "PATTERNS", "UVAtlas", "uv_atlas", "region_field", "texel_regions",
           "sample_outfit", "paint_albedo", "garment_texels", "hair_texels", "vertex_albedo"]

ALBEDO_MIN, ALBEDO_MAX = 0.02, 0.9
PATTERNS = ("plain", "stripes", "checks", "noise", "blobs")

_HAIR_SRGB = np.array([[20, 17, 15], [45, 32, 25], [85, 60, 40], [140, 100, 60], [200, 165, 110],
                       [150, 70, 35], [170, 165, 160]], dtype=np.float64) / 255.0
_HAIR_P = np.array([0.28, 0.28, 0.16, 0.08, 0.08, 0.05, 0.07])
_IRIS_SRGB = np.array([[60, 38, 20], [100, 70, 40], [70, 100, 130], [80, 100, 60]], dtype=np.float64) / 255.0
_GARMENT_FAMILIES = {  # sRGB anchors of common garment colours
    "denim": (0.25, 0.33, 0.5), "navy": (0.12, 0.14, 0.28), "khaki": (0.72, 0.64, 0.48),
    "olive": (0.38, 0.4, 0.25), "burgundy": (0.45, 0.12, 0.17), "brown": (0.4, 0.28, 0.2),
    "cream": (0.92, 0.88, 0.8), "charcoal": (0.2, 0.2, 0.22),
}


@dataclass(frozen=True)
class UVAtlas:
    """Per-texel lookup tables of a body's UV layout (see module docstring).

    Attributes:
        size: texture side S.
        texel_vertex: (S·S,) int64 nearest vertex of every texel (row-major, row 0 = v = 1).
        texel_tri: (S·S, 3) int64 vertices of the triangle of every texel.
        texel_bary: (S·S, 3) float32 barycentrics in that triangle.
        texel_pos: (S·S, 3) float32 zero-pose positions (metres).
        vertex_texel: (V,) int64 a texel inside the UV triangles of each vertex.
        parts: (V,) int64 Anny part ids (:data:`relightnet.body.albedo.ANNY_PARTS`).
        texel_source: (S·S,) int64 the island texel whose triangle, barycentrics and position a texel
            copies (itself inside the islands).
    """

    size: int
    texel_vertex: np.ndarray
    texel_tri: np.ndarray
    texel_bary: np.ndarray
    texel_pos: np.ndarray
    vertex_texel: np.ndarray
    parts: np.ndarray
    texel_source: np.ndarray


def uv_atlas(body, size: int = 512) -> UVAtlas:
    """Rasterize a body model's UV layout into per-texel tables (about 0.3 s at 512²).

    Args:
        body: :class:`~relightnet.body.AnnyBody` (or any model with ``uv``, ``uv_faces``, ``faces``).
        size: texture side S.
    """
    from scipy import ndimage

    if int(size) != size or size < 8:
        raise InputError(f"texture size: expected an integer >= 8, got {size!r}")
    uv = body.uv.detach().cpu().float()
    uv_faces = body.uv_faces.cpu()
    faces = body.faces.cpu()
    clip = torch.cat([uv * 2 - 1, torch.zeros(len(uv), 1), torch.ones(len(uv), 1)], dim=1)
    frags = rasterize(clip[None], uv_faces, (size, size))
    n = size * size
    face = torch.full((n,), -1, dtype=torch.int64).index_copy_(0, frags.pix, frags.pix_face)
    bary = torch.zeros(n, 3).index_copy_(0, frags.pix, frags.pix_bary.float())
    covered = (face >= 0).numpy().reshape(size, size)
    _, (ri, ci) = ndimage.distance_transform_edt(~covered, return_indices=True)
    src = torch.as_tensor((ri * size + ci).reshape(-1))
    face, bary = face[src], bary[src]
    with torch.no_grad():
        rest = body().verts[0].detach().cpu().float()
    tri = faces[face]  # (n, 3)
    pos = (rest[tri] * bary[:, :, None]).sum(1)
    texel_vertex = tri.gather(1, bary.argmax(1, keepdim=True))[:, 0]
    # A texel inside a triangle of each vertex: the triangle's UV centroid, nearest texel.
    cen = uv[uv_faces].mean(1)  # (F, 2)
    col = (cen[:, 0] * size).long().clamp(0, size - 1)
    row = ((1 - cen[:, 1]) * size).long().clamp(0, size - 1)
    vt = torch.zeros(body.num_verts, dtype=torch.int64)
    for k in range(3):
        vt[faces[:, k]] = row * size + col
    return UVAtlas(int(size), texel_vertex.numpy(), tri.numpy(), bary.numpy().astype(np.float32),
                   pos.numpy().astype(np.float32), vt.numpy(), anny_part_labels(body).numpy(),
                   src.numpy().astype(np.int64))


def region_field(faces, regions, n_regions: int = len(REGIONS), iters: int = 4) -> np.ndarray:
    """Smoothed one-hot region labels: (V,) ids → (V, R) float32 field (rows sum to 1).

    Each step replaces a vertex's value by the mean of itself and its edge neighbours, so
    after ``iters`` steps the labels are blurred over about ``iters`` rings (~1–2 cm on
    Anny); the arg-max of the interpolated field draws smooth boundaries.
    """
    import scipy.sparse

    regions = np.asarray(regions, dtype=np.int64)
    f = np.asarray(faces, dtype=np.int64)
    n = len(regions)
    i = np.concatenate([f[:, 0], f[:, 1], f[:, 2], f[:, 1], f[:, 2], f[:, 0], np.arange(n)])
    j = np.concatenate([f[:, 1], f[:, 2], f[:, 0], f[:, 0], f[:, 1], f[:, 2], np.arange(n)])
    A = scipy.sparse.csr_matrix((np.ones(len(i), dtype=np.float32), (i, j)), shape=(n, n))
    A.data[:] = 1.0  # duplicate edges count once
    A = scipy.sparse.diags(1.0 / np.asarray(A.sum(1)).ravel()) @ A
    x = np.eye(n_regions, dtype=np.float32)[regions]
    for _ in range(int(iters)):
        x = A @ x
    return np.asarray(x, dtype=np.float32)


def texel_regions(atlas: UVAtlas, regions) -> np.ndarray:
    """(S·S,) region id of every texel: nearest vertex for (V,) ids, interpolated arg-max for a (V, R) field."""
    regions = np.asarray(regions)
    if regions.ndim == 1:
        return regions[atlas.texel_vertex]
    return np.einsum("nk,nkr->nr", atlas.texel_bary, regions[atlas.texel_tri]).argmax(1)


def _garment_color(rng: np.random.Generator, region: str) -> np.ndarray:
    """A linear-RGB garment colour: neutrals, common garment families, or any hue."""
    r = rng.uniform()
    fam = list(_GARMENT_FAMILIES.values())[int(rng.integers(len(_GARMENT_FAMILIES)))]
    if r < 0.35:
        v = rng.uniform(0.06, 0.95)
        c = np.full(3, v) + rng.normal(0.0, 0.015, 3)
    elif r < 0.6 or (region == "bottom" and r < 0.8):
        c = np.asarray(fam) * np.exp(rng.normal(0.0, 0.12, 3))
    else:
        c = np.array(colorsys.hsv_to_rgb(rng.uniform(), rng.uniform(0.2, 0.9), rng.uniform(0.2, 0.95)))
    return srgb_to_linear_np(c, clip=True)


def sample_outfit(rng: np.random.Generator) -> dict:
    """Draw the look of one person: skin, hair, garments and their patterns.

    Returns:
        A JSON-serialisable dict: ``skin_tone``, ``skin`` (3,), ``hair`` (3,) or None (bald),
        ``iris`` (3,), ``sleeves``, ``legs`` (for :func:`relightnet.body.albedo.region_labels`), and
        per garment region (``top``, ``bottom``, ``shoes``) a dict with ``color``,
        ``color2``, ``pattern`` and the pattern's parameters. Every draw happens in a fixed
        order whatever the outcome, so one choice does not shift the others.
    """
    tone = float(rng.beta(1.1, 1.4))
    skin = skin_color(tone).double().numpy() * np.exp(rng.normal(0.0, 0.04, 3))
    hair_srgb = _HAIR_SRGB[int(rng.choice(len(_HAIR_SRGB), p=_HAIR_P))]
    hair_c = srgb_to_linear_np(hair_srgb, clip=True) * np.exp(rng.normal(0, 0.1, 3))
    bald = bool(rng.uniform() < 0.08)
    iris = srgb_to_linear_np(_IRIS_SRGB[int(rng.integers(len(_IRIS_SRGB)))], clip=True)
    sleeves = ("none", "short", "elbow", "long")[int(rng.choice(4, p=[0.15, 0.35, 0.1, 0.4]))]
    legs = ("shorts", "knee", "long")[int(rng.choice(3, p=[0.15, 0.15, 0.7]))]
    out = {"skin_tone": tone, "skin": skin.tolist(), "hair": None if bald else hair_c.tolist(),
           "iris": iris.tolist(), "sleeves": sleeves, "legs": legs}
    probs = {"top": [0.4, 0.2, 0.12, 0.13, 0.15], "bottom": [0.6, 0.08, 0.1, 0.17, 0.05],
             "shoes": [0.8, 0.05, 0.0, 0.15, 0.0]}
    for region in ("top", "bottom", "shoes"):
        c1, c2 = _garment_color(rng, region), _garment_color(rng, region)
        if rng.uniform() < 0.4:  # a tone-on-tone second colour
            c2 = c1 * rng.uniform(0.35, 0.8)
        ang = rng.uniform(0, math.pi)
        g = {
            "color": c1.tolist(), "color2": c2.tolist(),
            "pattern": PATTERNS[int(rng.choice(len(PATTERNS), p=probs[region]))],
            "direction": [math.sin(ang), math.cos(ang), 0.0] if rng.uniform() < 0.35 else [0.0, 1.0, 0.0],
            "period": float(math.exp(rng.uniform(math.log(0.01), math.log(0.1)))),
            "duty": float(rng.uniform(0.2, 0.6)),
            "noise_scale": float(math.exp(rng.uniform(math.log(0.02), math.log(0.25)))),
            "noise_sharp": bool(rng.uniform() < 0.4),
            "n_blobs": int(rng.integers(3, 40)),
            "blob_radius": float(rng.uniform(0.012, 0.08)),
            "fabric": float(rng.uniform(0.02, 0.12)),
            "seed": int(rng.integers(2**31 - 1)),
        }
        out[region] = g
    out["seed"] = int(rng.integers(2**31 - 1))
    return out


def _distinct(repeat: torch.Tensor | None) -> tuple[torch.Tensor | None, torch.Tensor | None]:
    """(rows that repeat no other (U,), the one of them each row (N,) repeats as an index into them) for
    ``repeat`` (N,), the row whose point each row repeats (itself for a distinct point); (None, None) for None."""
    if repeat is None:
        return None, None
    own = repeat == torch.arange(len(repeat))
    return torch.nonzero(own).flatten(), (torch.cumsum(own, 0) - 1)[repeat]


def _selection_repeats(atlas: UVAtlas, sel: torch.Tensor) -> torch.Tensor:
    """(N,) for the texels ``sel`` (S·S,) bool: the row (in the selection) of the texel whose position each one
    copies (:attr:`UVAtlas.texel_source`), itself where that texel is not selected."""
    idx = torch.nonzero(sel).flatten()
    slot = torch.full((sel.shape[0],), -1, dtype=torch.int64)
    slot[idx] = torch.arange(len(idx))
    r = slot[torch.from_numpy(atlas.texel_source)[idx]]
    return torch.where(r >= 0, r, torch.arange(len(idx)))


def _noise3d(pos: torch.Tensor, scale: float, rng: np.random.Generator, channels: int = 1,
             octaves: int = 3, repeat: torch.Tensor | None = None) -> torch.Tensor:
    """Smooth value noise in about [−1, 1] at points (N, 3) metres, base wavelength ``scale``; a row that
    ``repeat`` (N,) says repeats another's point takes its value (the box and the draws are the same)."""
    first, inv = _distinct(repeat)
    if first is not None:
        return _noise3d(pos[first], scale, rng, channels, octaves)[inv]
    lo, hi = torch.aminmax(pos, dim=0)  # one pass: over twice as fast as amin and amax
    lo, hi = lo - 0.05, hi + 0.05
    out = torch.zeros(pos.shape[0], channels)
    amp, total = 1.0, 0.0
    for o in range(octaves):
        s = scale / 2**o
        n = [max(2, min(96, int(math.ceil(float(hi[i] - lo[i]) / s)) + 2)) for i in range(3)]
        grid = torch.from_numpy(rng.uniform(-1, 1, (1, channels, n[2], n[1], n[0])).astype(np.float32))
        g = ((pos - lo) / (hi - lo) * 2 - 1)[None, None, None]  # (1, 1, 1, N, 3) as (x, y, z)
        out += amp * torch.nn.functional.grid_sample(grid, g, align_corners=True)[0, :, 0, 0].T
        total += amp
        amp *= 0.5
    return out / total * 1.7


def _pattern_mask(g: dict, pos: torch.Tensor, rng: np.random.Generator, repeat=None) -> torch.Tensor:
    """(N,) weight of the second colour at the points ``pos`` for a garment's pattern (``repeat``: _noise3d)."""
    p = g["pattern"]
    if p == "plain":
        return torch.zeros(pos.shape[0])
    if p in ("stripes", "checks"):
        d = torch.tensor(g["direction"], dtype=torch.float32)
        s = torch.frac(pos @ d / g["period"])
        m = ((s < g["duty"]).float())
        if p == "checks":
            d2 = torch.linalg.cross(d, torch.tensor([0.0, 0.0, 1.0]))
            d2 = d2 / d2.norm().clamp_min(1e-6)
            m2 = (torch.frac(pos @ d2 / g["period"]) < g["duty"]).float()
            m = 0.5 * (m + m2)
        return m
    if p == "noise":
        n = _noise3d(pos, g["noise_scale"], rng, repeat=repeat)[:, 0]
        return (n > 0.1).float() if g["noise_sharp"] else (n * 0.5 + 0.5).clamp(0, 1)
    if p == "blobs":
        idx = rng.integers(0, pos.shape[0], g["n_blobs"])
        centres = pos[torch.as_tensor(idx)]
        radii = torch.as_tensor(g["blob_radius"] * rng.uniform(0.6, 1.4, g["n_blobs"]), dtype=torch.float32)
        first, inv = _distinct(repeat)
        pts = pos if first is None else pos[first]
        warp = _noise3d(pts, 2 * g["blob_radius"], rng, octaves=2)[:, 0] * 0.3 * g["blob_radius"]
        m = torch.zeros(pts.shape[0])
        for c, r in zip(centres, radii, strict=True):
            d = (pts - c).norm(dim=1) + warp
            m = torch.maximum(m, (d < r).float())
        return m if first is None else m[inv]
    raise InputError(f"pattern: expected one of {PATTERNS}, got {p!r}")


def paint_albedo(atlas: UVAtlas, regions, outfit: dict, texels=None) -> torch.Tensor:
    """Paint an outfit into a UV texture.

    Args:
        atlas: the body's :class:`UVAtlas`.
        regions: (V,) region ids into :data:`relightnet.body.albedo.REGIONS`
            (``region_labels(body, outfit["sleeves"], outfit["legs"], hair)``), or their
            (V, R) :func:`region_field` (smooth garment edges).
        outfit: from :func:`sample_outfit`.
        texels: (S·S,) ``texel_regions(atlas, regions)`` when the caller keeps it for its
            variant (then ``regions`` is not read); None computes it.

    Returns:
        (S, S, 3) float32 linear albedo in [ALBEDO_MIN, ALBEDO_MAX], row 0 = v = 1.
    """
    S = atlas.size
    reg = torch.as_tensor(texel_regions(atlas, regions) if texels is None else texels)
    part = atlas.parts[atlas.texel_vertex]
    pos = torch.from_numpy(atlas.texel_pos)
    rng = np.random.default_rng(outfit["seed"])
    tex = torch.zeros(S * S, 3)
    ids = {r: i for i, r in enumerate(REGIONS)}
    # Skin: tone, low-frequency mottling.
    sel = reg == ids["skin"]
    mott = 1 + 0.04 * _noise3d(pos[sel], 0.05, rng, octaves=2, repeat=_selection_repeats(atlas, sel))
    tex[sel] = torch.tensor(outfit["skin"], dtype=torch.float32) * mott
    # Hair: colour with streaks along y.
    sel = reg == ids["hair"]
    if outfit["hair"] is not None and bool(sel.any()):
        tex[sel] = hair_texels(outfit["hair"], pos[sel], rng, _selection_repeats(atlas, sel))
    elif bool(sel.any()):
        tex[sel] = torch.tensor(outfit["skin"], dtype=torch.float32)
    for region in ("top", "bottom", "shoes"):
        sel = reg == ids[region]
        if not bool(sel.any()):
            continue
        tex[sel] = garment_texels(outfit[region], pos[sel], _selection_repeats(atlas, sel))
    # Eyes and mouth.
    pid = {p: i for i, p in enumerate(ANNY_PARTS)}
    for names, col in ((("eye_front.L", "eye_front.R"), outfit["iris"]),
                       (("eye_back.L", "eye_back.R"), [0.72, 0.7, 0.66]),
                       (("mouth_cavity", "tongue"), [0.35, 0.08, 0.08])):
        sel = torch.as_tensor(np.isin(part, [pid[n] for n in names]))
        tex[sel] = torch.tensor(col, dtype=torch.float32)
    return tex.clamp(ALBEDO_MIN, ALBEDO_MAX).reshape(S, S, 3).contiguous()


def garment_texels(g: dict, pos: torch.Tensor, repeat=None) -> torch.Tensor:
    """(N, 3) colours of garment ``g`` (a region dict of :func:`sample_outfit`) at 3D points (N, 3) metres:
    its two colours mixed by its pattern, times the fabric variation and grain (not yet clamped).
    ``repeat``: None, or (N,) int64 the row whose point each row repeats (itself for a distinct point;
    the atlas's padding texels repeat island texels): a repeated point's pattern is evaluated once."""
    grng = np.random.default_rng(g["seed"])
    m = _pattern_mask(g, pos, grng, repeat)[:, None]
    c1 = torch.tensor(g["color"], dtype=torch.float32)
    c2 = torch.tensor(g["color2"], dtype=torch.float32)
    fabric = 1 + g["fabric"] * _noise3d(pos, 0.15, grng, octaves=2, repeat=repeat)
    grain = 1 + 0.03 * torch.from_numpy(grng.standard_normal((pos.shape[0], 1)).astype(np.float32))
    return (c1 * (1 - m) + c2 * m) * fabric * grain


def hair_texels(color, pos: torch.Tensor, rng: np.random.Generator, repeat=None) -> torch.Tensor:
    """(N, 3) hair colour ``color`` (3,) with streaks along y at 3D points (N, 3) metres (not yet clamped);
    ``repeat`` as for :func:`garment_texels`."""
    streak = _noise3d(pos * torch.tensor([1.0, 0.25, 1.0]), 0.01, rng, octaves=2, repeat=repeat)
    return torch.tensor(color, dtype=torch.float32) * (1 + 0.25 * streak)


def vertex_albedo(atlas: UVAtlas, tex: torch.Tensor) -> torch.Tensor:
    """(V, 3) per-vertex albedo read from a texture painted with :func:`paint_albedo`."""
    return tex.reshape(-1, 3)[torch.as_tensor(atlas.vertex_texel)]
