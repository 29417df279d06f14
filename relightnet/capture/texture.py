"""A de-lit albedo texture from the frames of a fitted person.

Every frame adds samples to the texels it sees (:func:`frame_samples`):

1. each texel of the UV islands (:class:`TexelTable`) is placed on the posed, offset mesh at
   its barycentrics and projected into the frame;
2. it is *seen* when it faces the camera (cosine above :attr:`TextureOptions.min_cos`), lies in
   the frame, and its depth is within a tolerance of the rasterized depth at its pixel (nothing in
   front of it): :attr:`TextureOptions.depth_tol` plus how far the surface's depth can change across
   the pixel (its footprint ``z / f`` times the tangent of the view angle, twice over), so a
   grazing surface still sees itself and an eyeball behind its lid does not;
3. its colour is the frame's linear RGB at the projected point (bilinear), divided by the
   shading of the captured geometry under that frame's light, ``S = T · L`` (PRT transport with
   occlusion at the vertices, interpolated) — what remains is albedo on the light's scale, so
   the exposure is kept;
4. its weight is ``cos² × edge × registration⁴ × shade``: the squared view cosine (a grazing view smears a
   texel over few pixels), the distance inside the person's mask ramped over
   :attr:`TextureOptions.edge_share` of the person's height (0 outside the mask: the fitted body
   strays over the background at the outline), the frame's registration (the IoU of the fitted
   mesh's coverage with the mask, to the fourth power: a frame whose fit slipped paints the wrong
   texels, and weighs less), and the shading relative to the frame's median
   (a dark, self-shadowed texel divides noise by a small number). A sample that touches a clipped
   pixel (any channel at :attr:`TextureOptions.clip_level`, or a neighbour's) weighs 0: clipping
   cuts the colour, and dividing it by the shading would darken the texel.

:class:`TextureFusion` keeps, per texel, the :attr:`TextureOptions.top_k` samples of largest
weight (bounded memory whatever the length) and the sum of all weights; the texel's albedo is
the weighted median of its kept samples per channel (robust to a frame whose fit slipped), its
confidence the sum of weights.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from ..checks import InputError, check_shape, sh_order_from_count
from ..raster import Camera, rasterize, screen_box
from ..raster.camera import ndc_to_pixel

__all__ = ["TextureOptions", "TexelTable", "TexelSamples", "TextureFusion", "texel_table", "frame_samples",
           "weighted_median"]


@dataclass(frozen=True)
class TextureOptions:
    """How the texture is captured.

    Attributes:
        size: texture side S in texels (Anny's UV layout).
        n_dirs: PRT directions of each frame's transport.
        top_k: samples kept per texel for the weighted median.
        min_cos: smallest view cosine of a texel that is sampled.
        depth_tol: metres a texel may lie behind the rasterized surface and still be seen, beyond the
            depth change across its pixel.
        edge_share: the mask-edge ramp, as a share of the person's height in the frame.
        clip_level: linear value at or above which a pixel counts as clipped.
    """

    size: int = 1024
    n_dirs: int = 64
    top_k: int = 12
    min_cos: float = 0.2
    depth_tol: float = 0.004
    edge_share: float = 0.012
    clip_level: float = 0.985

    def __post_init__(self) -> None:
        if isinstance(self.size, bool) or int(self.size) != self.size or not 64 <= self.size <= 4096:
            raise InputError(f"texture size: expected an integer in [64, 4096], got {self.size!r}")
        if int(self.top_k) != self.top_k or not 1 <= self.top_k <= 64:
            raise InputError(f"top_k: expected an integer in [1, 64], got {self.top_k!r}")
        if int(self.n_dirs) != self.n_dirs or self.n_dirs < 8:
            raise InputError(f"n_dirs: expected an integer >= 8, got {self.n_dirs!r}")


@dataclass(frozen=True, eq=False)
class TexelTable:
    """The texels of a body's UV islands, where each lies on the mesh.

    Attributes:
        size: texture side S.
        index: (M,) int64 flat texel indices (row-major, row 0 = v = 1) of the island texels.
        tri: (M, 3) int64 vertices of each texel's triangle. bary: (M, 3) float32 its barycentrics.
        source: (S·S,) int64 the island texel each texel copies (itself inside the islands; the
            nearest island texel in the gutters between islands).
        face: (M,) int64 each texel's face (the row of ``faces`` whose vertices are ``tri``).
    """

    size: int
    index: torch.Tensor
    tri: torch.Tensor
    bary: torch.Tensor
    source: torch.Tensor
    face: torch.Tensor


def texel_table(atlas, faces: torch.Tensor) -> TexelTable:
    """The island texels of a :class:`~relightnet.data.textures.UVAtlas` of the mesh with (F, 3) ``faces``."""
    src = torch.as_tensor(atlas.texel_source)
    index = torch.nonzero(src == torch.arange(src.numel())).squeeze(1)
    tri = torch.as_tensor(atlas.texel_tri)[index]
    n = int(faces.max()) + 1
    key = (faces[:, 0] * n + faces[:, 1]) * n + faces[:, 2]
    order = key.argsort()
    texel_key = (tri[:, 0] * n + tri[:, 1]) * n + tri[:, 2]
    at = torch.searchsorted(key[order], texel_key).clamp_max(len(key) - 1)
    face = order[at]
    if not torch.equal(key[face], texel_key):
        raise InputError("atlas: its texel triangles are not faces of this mesh")
    return TexelTable(int(atlas.size), index, tri, torch.as_tensor(atlas.texel_bary)[index].float(), src, face)


@dataclass(frozen=True, eq=False)
class TexelSamples:
    """One frame's samples: ``texel`` (N,) indices into :attr:`TexelTable.index`'s M texels,
    ``albedo`` (N, 3) de-lit linear RGB, ``raw`` (N, 3) the frame's linear RGB, ``weight`` (N,)."""

    texel: torch.Tensor
    albedo: torch.Tensor
    raw: torch.Tensor
    weight: torch.Tensor


def _edge_weight(mask: torch.Tensor, share: float) -> torch.Tensor:
    """(H, W) float: 0 outside the mask, rising to 1 over ``share`` of the person's height inside."""
    from scipy import ndimage

    m = mask.numpy()
    rows, cols = np.nonzero(m.any(1))[0], np.nonzero(m.any(0))[0]
    out = np.zeros(m.shape, np.float32)
    if rows.size == 0:
        return torch.from_numpy(out)
    r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    ramp = max(2.0, share * (r1 - r0))
    crop = np.pad(m[r0:r1, c0:c1], 1)  # the frame's border counts as outside
    dist = ndimage.distance_transform_edt(crop)[1:-1, 1:-1]
    out[r0:r1, c0:c1] = np.clip((dist - 0.5) / ramp, 0.0, 1.0)
    return torch.from_numpy(out)


def _registration(win, depth: torch.Tensor, mask: torch.Tensor) -> float:
    """IoU of the fitted mesh's coverage with the person's mask (in the mesh's box, the mask outside it counted
    as missed): how well the frame's fit is registered."""
    cover = torch.isfinite(depth)
    inside = mask[win.top:win.top + win.height, win.left:win.left + win.width]
    both = float((cover & inside).sum())
    union = float((cover | inside).sum()) + float(mask.sum()) - float(inside.sum())
    return both / max(union, 1.0)


def _clipped(image: torch.Tensor, level: float) -> torch.Tensor:
    """(H, W) float: 1 where a pixel or one of its 8 neighbours is clipped (any channel at ``level``), so a
    bilinear sample never mixes a clipped pixel in."""
    hot = (image.amax(0) >= level).float()[None, None]
    return F.max_pool2d(hot, 3, stride=1, padding=1)[0, 0]


def _bilinear(img: torch.Tensor, uv: torch.Tensor) -> torch.Tensor:
    """(C, H, W) image at (N, 2) continuous pixel points (u right, v down) → (N, C)."""
    H, W = img.shape[-2:]
    grid = torch.stack([uv[:, 0] * (2.0 / W) - 1, uv[:, 1] * (2.0 / H) - 1], -1)[None, None]
    return F.grid_sample(img[None], grid.to(img), align_corners=False, padding_mode="border")[0, :, 0].T


def _visible_depth(camera: Camera, verts: torch.Tensor, faces: torch.Tensor):
    """The mesh rasterized in its box: (window, dense (h, w) view depth, +inf off the mesh)."""
    vc = camera.transform(verts[None])
    win = screen_box(vc, faces, camera.size)
    if win is None:
        return None, None
    frags = rasterize(vc, faces, camera.size, window=win)
    return win, camera.depth_to_view(frags.depth)[0]


def _seen_texels(table: TexelTable, verts, normals, faces, camera: Camera, win, depth, options: TextureOptions):
    """Steps 1–2: ``(index (N,) into the M texels, pixel points (N, 2), view cosines (N,))`` of the texels the
    frame sees, or None. The cosine is tested first at the vertices (V of them, not M texels): only texels
    whose face has a vertex that passes are placed on the mesh and projected."""
    to_cam_v = F.normalize(camera.position[0].to(verts) - verts, dim=-1)
    cos_v = (normals * to_cam_v).sum(-1)
    face_ok = (cos_v[faces] > options.min_cos).any(1)
    sel = torch.nonzero(face_ok[table.face]).squeeze(1)
    tri, bary = table.tri[sel], table.bary[sel]
    pos = torch.einsum("mk,mkc->mc", bary, verts[tri])
    nrm = F.normalize(torch.einsum("mk,mkc->mc", bary, normals[tri]), dim=-1)
    cos = (nrm * F.normalize(camera.position[0].to(pos) - pos, dim=-1)).sum(-1)
    ok = cos > options.min_cos
    sel, pos, cos = sel[ok], pos[ok], cos[ok]
    c = camera.transform(pos)[0]
    uv = ndc_to_pixel(c[:, :2] / c[:, 3:], camera.size)
    zt = -camera.world_to_view(pos)[0, :, 2]
    col = uv[:, 0].floor().long() - win.left
    row = uv[:, 1].floor().long() - win.top
    inside = torch.nonzero((col >= 0) & (col < win.width) & (row >= 0) & (row < win.height)).squeeze(1)
    zb = depth[row[inside], col[inside]]
    zi, ci = zt[inside], cos[inside]
    slope = (1 - ci.square()).clamp_min(0).sqrt() / ci  # tan of the view angle
    tol = options.depth_tol + 2 * zi / float(camera.proj[0, 0, 0] * camera.size[1] / 2) * slope
    keep = inside[torch.isfinite(zb) & (zi <= zb + tol)]
    if keep.numel() == 0:
        return None
    return sel[keep], uv[keep], cos[keep]


def frame_samples(table: TexelTable, verts: torch.Tensor, normals: torch.Tensor, faces: torch.Tensor,
                  light: torch.Tensor, camera: Camera, image: torch.Tensor, mask: torch.Tensor,
                  options: TextureOptions = TextureOptions()) -> TexelSamples | None:
    """The samples of one frame (module docstring, steps 1–4).

    Args:
        table: :func:`texel_table` of the body's atlas.
        verts: (V, 3) posed (and offset) vertices in the camera's world frame. normals: (V, 3) unit.
        faces: (F, 3) int64.
        light: (K, 3) the frame's SH light, camera-relative (the light frame of ``camera``'s view).
        camera: one camera whose ``size`` (H, W) is the frame's.
        image: (3, H, W) linear RGB. mask: (H, W) bool, the person.
        options: :class:`TextureOptions`.

    Returns:
        :class:`TexelSamples`, or None when the frame sees no texel.
    """
    from ..prt import PrtSettings, vertex_transport
    from ..render.frame import light_in_world
    from ..render.shading import shading

    H, W = camera.size
    check_shape(verts, ["V", 3], name="verts")
    check_shape(image, [3, H, W], name="image")
    check_shape(mask, [H, W], name="mask")
    win, depth = _visible_depth(camera, verts, faces)
    if win is None or not bool(mask.any()):
        return None
    seen = _seen_texels(table, verts, normals, faces, camera, win, depth, options)
    if seen is None:
        return None
    sel, uv, cos = seen
    tri, bary = table.tri[sel], table.bary[sel]
    lmax = sh_order_from_count(light.shape[-2], "light")
    # The vertices of the texels kept: a sub-pixel triangle covers no pixel centre, yet its texels are seen.
    need = torch.zeros(verts.shape[0], dtype=torch.bool)
    need[tri.reshape(-1)] = True
    T = vertex_transport(verts, faces, normals, lmax=lmax, prt=PrtSettings(n_dirs=options.n_dirs),
                         vertices=torch.nonzero(need)[:, 0], manifold="ignore")
    L = light_in_world(light.float(), camera)[0]
    s_v = shading(T, L)  # (V, 3)
    s = torch.einsum("mk,mkc->mc", bary, s_v[tri]).clamp_min(1e-4)
    rgb = _bilinear(image.float(), uv)
    edge = _bilinear(_edge_weight(mask, options.edge_share)[None], uv)[:, 0]
    lum = s.mean(1)
    shade = (lum / (0.5 * lum.median().clamp_min(1e-4))).clamp(0, 1)
    clipped = _bilinear(_clipped(image, options.clip_level)[None], uv)[:, 0] > 0
    w = cos.square() * edge * shade * (~clipped) * _registration(win, depth, mask) ** 4
    good = w > 1e-4
    return TexelSamples(sel[good], (rgb / s)[good], rgb[good], w[good])


def weighted_median(values: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """Per-row weighted median: (N, K, C) values, (N, K) weights ≥ 0 → (N, C) (0 where all weights are 0).

    The value at which the weights sorted by value first reach half of the row's total.
    """
    d = check_shape(values, ["N", "K", "C"], name="values")
    check_shape(weights, [d["N"], d["K"]], name="weights")
    v, order = values.sort(dim=1)
    w = weights[:, :, None].expand_as(values).gather(1, order)
    cum = w.cumsum(1)
    half = 0.5 * cum[:, -1:, :]
    idx = (cum < half).sum(1, keepdim=True).clamp_max(d["K"] - 1)
    return v.gather(1, idx)[:, 0] * (cum[:, -1] > 0)


class TextureFusion:
    """Fuses :class:`TexelSamples` over frames (module docstring).

    Args:
        n_texels: M, the island texels. top_k: samples kept per texel. raw: also fuse the frames' raw
            colours (the texture copied without de-lighting, for evaluation).
    """

    def __init__(self, n_texels: int, top_k: int = 8, raw: bool = False) -> None:
        self.weight = torch.zeros(n_texels, top_k)
        self.albedo = torch.zeros(n_texels, top_k, 3, dtype=torch.float16)
        self.raw = torch.zeros(n_texels, top_k, 3, dtype=torch.float16) if raw else None
        self.total = torch.zeros(n_texels)
        self.frames = torch.zeros(n_texels, dtype=torch.int32)

    def add(self, s: TexelSamples) -> None:
        """Add one frame's samples (each texel at most once)."""
        self.total.index_add_(0, s.texel, s.weight)
        self.frames.index_add_(0, s.texel, torch.ones_like(s.texel, dtype=torch.int32))
        wk = self.weight[s.texel]
        slot = wk.argmin(1)
        better = s.weight > wk.gather(1, slot[:, None])[:, 0]
        t, k = s.texel[better], slot[better]
        self.weight[t, k] = s.weight[better]
        self.albedo[t, k] = s.albedo[better].clamp(0, 60000).half()
        if self.raw is not None:
            self.raw[t, k] = s.raw[better].half()

    def result(self, which: str = "albedo") -> torch.Tensor:
        """(M, 3) fused values (``"albedo"`` or ``"raw"``), 0 where never seen."""
        vals = self.albedo if which == "albedo" else self.raw
        if vals is None:
            raise InputError("raw: this fusion was made without raw=True")
        return weighted_median(vals.float(), self.weight)
