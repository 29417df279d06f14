"""Geometry beyond the body: per-vertex offsets along the normal (the SMPL+D idea).

An offset d_v moves vertex v along its posed normal: ``v' = v + d_v n_v``. Applied after
skinning, it poses with the body in every frame (the normal turns with the skinned surface).

:func:`solve_offsets` finds one offset field for a fitted clip from the person's silhouettes
(Alldieck et al. 2018, "Video Based Reconstruction of 3D People Models"): the frames' poses are
fixed, the offset body's projected vertices should cover the masks as the fit's silhouette term
measures (:func:`relightnet.fit.terms.silhouette_term`), the field is smooth over the mesh (a uniform
Laplacian), pulled to 0, bounded to [:data:`OFFSET_FLOOR`, ``bound``], and held within
:data:`SKIN_BOUND` of 0 on the face and the hands (skin carries no cloth).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass

import numpy as np
import torch

from ..checks import check_shape
from ..errors import InputError
from ..fit.camera import project_points
from ..fit.masks import PackedMasks
from ..fit.preview import fit_meshes
from ..fit.terms import outline_matches, silhouette_targets, silhouette_term
from ..raster import rasterize
from ..raster.camera import perspective_projection

__all__ = ["OFFSET_FLOOR", "OFFSET_UNIT", "SKIN_BOUND", "OffsetFit", "apply_offsets", "solve_offsets"]

log = logging.getLogger(__name__)

#: The most an offset may move a vertex inward (metres): the fitted body is about the person's size.
OFFSET_FLOOR = -0.01
#: Offsets on the face and the hands stay within ± this (metres).
SKIN_BOUND = 0.01
#: Offsets are measured in this unit (metres) by the smoothness and the pull to 0.
OFFSET_UNIT = 0.01
#: Outline points per frame of the silhouette term.
_OUTLINE_POINTS = 512
#: The outline points are matched to their nearest projected vertices every this many steps.
_MATCH_EVERY = 10
#: Outline points are matched to vertices whose normal is this close to square to the camera ray (|cos|).
_RIM = 0.4
#: The offsets are the free values averaged over this many rings of neighbours (:func:`_spread`).
_HOPS = 6


def apply_offsets(verts: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    """Move every vertex along its normal by its offset.

    Args:
        verts: (B, V, 3) posed positions. normals: (B, V, 3) unit posed normals.
        offsets: (V,) metres along the normal (positive: outward).

    Returns:
        (B, V, 3) displaced positions (differentiable in all three).
    """
    d = check_shape(verts, ["B", "V", 3], name="verts")
    check_shape(normals, [d["B"], d["V"], 3], name="normals")
    check_shape(offsets, [d["V"]], name="offsets")
    return verts + offsets.to(verts)[None, :, None] * normals


@dataclass(frozen=True, eq=False)
class OffsetFit:
    """Per-vertex offsets solved from a clip's silhouettes.

    Attributes:
        offsets: (V,) float32 metres along the posed normal (:func:`apply_offsets`).
        iou_body: mean silhouette IoU of the bare fitted body with the masks, over the frames used.
        iou_offset: the same for the offset body.
        frames: the frame indices used.
    """

    offsets: torch.Tensor
    iou_body: float
    iou_offset: float
    frames: tuple[int, ...]


def _packed(masks, result) -> PackedMasks:
    """The masks as :class:`PackedMasks` of the fit's T frames of (H, W)."""
    T, size = int(result.pose.shape[0]), tuple(int(s) for s in result.size)
    if isinstance(masks, PackedMasks):
        if len(masks) != T or tuple(masks.size) != size:
            raise InputError(f"masks: expected {T} masks of {size}, got {len(masks)} of {tuple(masks.size)}")
        return masks
    if not isinstance(masks, (torch.Tensor, np.ndarray)):
        raise InputError(f"masks: expected a (T, H, W) tensor or PackedMasks, got {type(masks).__name__}")
    check_shape(masks, [T, size[0], size[1]], name="masks")
    return PackedMasks.from_masks(masks)


def _pick_frames(packed: PackedMasks, result, n_frames: int) -> list[int]:
    """Up to ``n_frames`` frames showing the person, evenly spread over the clip."""
    if int(n_frames) < 1:
        raise InputError(f"n_frames: expected >= 1, got {n_frames}")
    seen = [t for t in range(len(packed)) if not bool(result.interpolated[t]) and packed[t:t + 1].nbytes > 0]
    if not seen:
        raise InputError("masks: no frame shows the person")
    pick = np.linspace(0, len(seen) - 1, min(int(n_frames), len(seen))).round().astype(int)
    return [seen[i] for i in sorted(set(pick.tolist()))]


def _skin(body) -> torch.Tensor:
    """(V,) bool: the face and the hands (Anny's head, eye, mouth and hand parts, less the scalp)."""
    from ..body.albedo import ANNY_PARTS, REGIONS, anny_part_labels, region_labels

    parts = anny_part_labels(body)
    region = region_labels(body, parts=parts)
    not_skin = torch.tensor([ANNY_PARTS.index(p) for p in ("body", "foot.L", "foot.R")])
    return ~torch.isin(parts, not_skin) & (region == REGIONS.index("skin"))


def _graph(faces: torch.Tensor, V: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The mesh's edges both ways, ``(src (E,), dst (E,), 1 / degree (V,))``, for :func:`_laplace`."""
    f = faces.long().cpu()
    e = torch.cat([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    key = torch.unique(torch.cat([e[:, 0] * V + e[:, 1], e[:, 1] * V + e[:, 0]]))
    src, dst = key // V, key % V
    return src, dst, 1.0 / torch.bincount(src, minlength=V).clamp_min(1).float()


def _laplace(u: torch.Tensor, graph) -> torch.Tensor:
    """(V,) the uniform Laplacian of (V,) values: each less the mean of its neighbours."""
    src, dst, inv_deg = graph
    return u - torch.zeros_like(u).index_add(0, src, u[dst]) * inv_deg


def _spread(z: torch.Tensor, graph, hops: int) -> torch.Tensor:
    """(V,) values averaged with their neighbours ``hops`` times (the offsets' parametrisation: a step on one
    vertex moves its neighbourhood, so what the outline sees reaches the vertices it does not)."""
    src, dst, inv_deg = graph
    w = 1.0 / (1.0 + 1.0 / inv_deg)
    for _ in range(hops):
        z = (z + torch.zeros_like(z).index_add(0, src, z[dst])) * w
    return z


def _subpixel(targets, work: torch.Tensor):
    """The targets with the outline where the mask's edge lies, half a pixel beyond the centres of its outline
    pixels (each point moved 0.5 px down the blurred mask's slope). Without it the fitted silhouette shrank
    by about that (the IoU of a synthetic grown body's offsets 0.94, with it 0.97)."""
    import torch.nn.functional as F

    blur = F.avg_pool2d(work.float()[:, None], 3, 1, 1, count_include_pad=False)
    gy, gx = torch.gradient(blur[:, 0], dim=(1, 2))
    g = torch.stack([gx, gy], 1)  # (B, 2, h, w): up the mask, i.e. inward
    H, W = work.shape[-2:]
    o = targets.outline
    grid = torch.stack([o[..., 0] * (2.0 / W) - 1, o[..., 1] * (2.0 / H) - 1], -1)[:, :, None]
    n = F.grid_sample(g, grid, align_corners=False)[..., 0].transpose(1, 2)  # (B, M, 2)
    n = n / n.norm(dim=-1, keepdim=True).clamp_min(1e-6)
    return dataclasses.replace(targets, outline=o - 0.5 * n)


def _working_camera(intrinsics, factor: tuple[float, float]) -> tuple[float, float, float, float]:
    """The fit's intrinsics in working pixels (image pixels × ``factor``)."""
    fx, fy, cx, cy = (float(x) for x in intrinsics)
    return fx * factor[0], fy * factor[1], cx * factor[0], cy * factor[1]


def _iou(verts: torch.Tensor, faces: torch.Tensor, intr, work: torch.Tensor) -> float:
    """Mean IoU of the (B, V, 3) meshes' silhouettes (working intrinsics) with the (B, h, w) masks."""
    from ..raster import Camera

    B, (h, w) = verts.shape[0], work.shape[-2:]
    P = perspective_projection(*intr, (h, w))
    cam = Camera(torch.eye(4)[None].expand(B, 4, 4), P.expand(B, 4, 4), (h, w))
    with torch.no_grad():
        sil = rasterize(cam.transform(verts), faces, (h, w)).mask
    inter = (sil & work).flatten(1).sum(1).double()
    union = (sil | work).flatten(1).sum(1).double().clamp_min(1)
    return float((inter / union).mean())


def _rim(verts: torch.Tensor, normals: torch.Tensor) -> torch.Tensor:
    """(B, V) bool: vertices whose normal is within :data:`_RIM` of square to the camera ray (the ones on the
    outline, and the ones an offset moves across the image)."""
    ray = verts / verts.norm(dim=-1, keepdim=True).clamp_min(1e-6)
    return (ray * normals).sum(-1).abs() < _RIM


def _matches(pixels: torch.Tensor, targets, rim: torch.Tensor) -> torch.Tensor:
    """(B, M) :func:`relightnet.fit.terms.outline_matches` among each frame's ``rim`` vertices, a frame at a time."""
    out = []
    for b in range(pixels.shape[0]):
        one = dataclasses.replace(targets, outside=targets.outside[b:b + 1], outline=targets.outline[b:b + 1],
                                  valid=targets.valid[b:b + 1])
        idx = torch.nonzero(rim[b]).flatten()
        idx = idx if len(idx) else torch.arange(pixels.shape[1])
        out.append(idx[outline_matches(pixels[b:b + 1, idx], one)])
    return torch.cat(out)


def _optimise(verts, normals, targets, intr, lo, hi, graph, iters: int, smooth: float, pull: float,
              lr: float) -> torch.Tensor:
    """(V,) offsets minimising the silhouette term + smoothness + pull by Adam: the offsets are :func:`_spread`
    free values clamped to (V,) [lo, hi]; ``intr`` in image pixels."""
    unit = verts.new_full((verts.shape[0],), 1.0 / targets.factor[1])  # the term in working pixels²
    z = torch.zeros(verts.shape[1], requires_grad=True)
    opt = torch.optim.Adam([z], lr=lr)
    matches, rim = None, _rim(verts, normals)
    for it in range(int(iters)):
        d = torch.minimum(torch.maximum(_spread(z, graph, _HOPS), lo), hi)
        pixels = project_points(verts + d[None, :, None] * normals, intr)
        if it % _MATCH_EVERY == 0:
            matches = _matches(pixels.detach(), targets, rim)
        u = d / OFFSET_UNIT
        sil = silhouette_term(pixels, targets, unit, matches).mean()
        e = sil + smooth * _laplace(u, graph).square().mean() + pull * u.square().mean()
        opt.zero_grad()
        e.backward()
        opt.step()
    with torch.no_grad():
        return torch.minimum(torch.maximum(_spread(z, graph, _HOPS), lo), hi)


def solve_offsets(result, fb, masks, n_frames: int = 16, iters: int = 150, bound: float = 0.12,
                  smooth: float = 100.0, pull: float = 0.002, lr: float = 0.003,
                  skin: torch.Tensor | None = None) -> OffsetFit:
    """Offsets along the normal that grow the fitted body to the person's silhouettes (SMPL+D).

    Args:
        result: a :class:`relightnet.fit.FitResult` of T frames of (H, W) (view space; the poses stay fixed).
        fb: the :class:`relightnet.fit.FitBody` it was fitted with.
        masks: (T, H, W) person masks in [0, 1] (above 0.5 is the person), or :class:`relightnet.fit.masks.PackedMasks`
            of T frames. Frames with an empty mask or ``result.interpolated`` are skipped.
        n_frames: at most this many frames, evenly spread over the clip, are fitted together (one: a photo).
        iters: Adam steps.
        bound: the largest outward offset (metres); the smallest is :data:`OFFSET_FLOOR`.
        smooth: weight of the squared uniform Laplacian of the offsets (mean over vertices, in
            :data:`OFFSET_UNIT`) against the silhouette term (squared working pixels).
        pull: weight of the mean squared offset (in :data:`OFFSET_UNIT`).
        lr: Adam's step (metres).
        skin: (V,) bool vertices held within ±:data:`SKIN_BOUND` (default: the face and the hands).

    Returns:
        :class:`OffsetFit`: offsets (V,) float32 metres, the IoUs of the bare and offset body, the frames used.
    """
    t0 = time.perf_counter()
    if not 0.0 <= float(bound) <= 1.0:
        raise InputError(f"bound: expected metres in [0, 1], got {bound}")
    packed = _packed(masks, result)
    frames = _pick_frames(packed, result, n_frames)
    chosen = PackedMasks(packed.size)
    for t in frames:
        chosen.append(packed[t:t + 1].unpack()[0])
    work, factor = chosen.working()
    targets = _subpixel(silhouette_targets(work, _OUTLINE_POINTS, size=result.size, height=None), work)
    sub = dataclasses.replace(result, pose=result.pose[frames], trans=result.trans[frames])
    out = fit_meshes(sub, fb)
    verts, normals, faces = out.verts.float(), out.normals.float(), out.faces
    V = verts.shape[1]
    skin = _skin(fb.body) if skin is None else skin.bool()
    check_shape(skin, [V], name="skin")
    hi = torch.where(skin, torch.tensor(SKIN_BOUND), torch.tensor(float(bound)))
    lo = torch.where(skin, torch.tensor(-SKIN_BOUND), torch.tensor(OFFSET_FLOOR))
    d = _optimise(verts, normals, targets, result.intrinsics, lo, hi, _graph(faces, V), iters, smooth, pull, lr)
    intr = _working_camera(result.intrinsics, factor)
    grown = apply_offsets(verts, normals, d)
    fit = OffsetFit(d.float(), _iou(verts, faces, intr, work), _iou(grown, faces, intr, work), tuple(frames))
    log.info("offsets: %d frames, %d steps in %.2f s; IoU %.3f -> %.3f", len(frames), iters,
             time.perf_counter() - t0, fit.iou_body, fit.iou_offset)
    return fit
