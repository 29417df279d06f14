"""The avatar's default albedo with smooth garment boundaries, and a measure of how jagged a boundary is.

:func:`relightnet.body.default_albedo` labels *vertices* with regions (skin, hair, top,
bottom, shoes) and paints each texel with the region of its nearest vertex, so every garment
edge (neckline, sleeves, waist, ankles, hairline) runs along triangle edges: a stair-stepped
zig-zag at the scale of the mesh. :func:`smooth_default_albedo` paints the same colours
through a smooth field instead: the one-hot region labels are blurred over the mesh
(:func:`relightnet.data.textures.region_field`) and every texel takes the arg-max of the
field interpolated at its barycentrics in its UV triangle
(:func:`relightnet.data.textures.texel_regions`), so boundaries are iso-lines of a smooth
field that cut through triangles. Eyes and mouth keep their vertex colours.

:func:`boundary_jaggedness` measures a rendered boundary between two regions: the contour of
one region's indicator (sub-pixel, marching squares) where it borders the other, against the
same contour smoothed along its length; a zig-zag deviates by about its amplitude, a smooth
curve by a fraction of a pixel.
"""

from __future__ import annotations

import numpy as np
import torch

from ..checks import InputError

__all__ = ["smooth_default_albedo", "boundary_jaggedness"]

_FACE_PARTS = ("eye_back.L", "eye_front.L", "eye_back.R", "eye_front.R", "eye_cavity.L", "eye_cavity.R",
               "mouth_cavity", "tongue")


def smooth_default_albedo(body, size: int = 1024, iters: int = 16):
    """Anny's default albedo (:func:`relightnet.body.default_albedo`'s colours) with smooth boundaries.

    Args:
        body: :class:`~relightnet.body.AnnyBody`.
        size: texture side S (1024: a texel is about 2.5 mm on the body, so the per-texel arg-max does not
            draw its own stair-steps in a close-up).
        iters: blur steps of the region field (16: about four vertex rings, which irons out the zig-zag of
            the vertex labels while keeping each boundary where it was).

    Returns:
        :class:`~relightnet.render.TexturedAlbedo` with an (S, S, 3) texture in Anny's UV layout.
    """
    from ..body import default_albedo
    from ..body.albedo import ANNY_PARTS, REGIONS, region_labels
    from ..data.textures import region_field, texel_regions, uv_atlas
    from ..render.frame import TexturedAlbedo

    regions = region_labels(body)
    vertex = default_albedo(body, texture_size=None, regions=regions).vertex
    atlas = uv_atlas(body, size)
    face_part = np.isin(atlas.parts, [ANNY_PARTS.index(p) for p in _FACE_PARTS])
    table = torch.zeros(len(REGIONS), 3)
    for r in range(len(REGIONS)):
        sel = np.nonzero((regions.numpy() == r) & ~face_part)[0]
        if len(sel):
            table[r] = vertex[int(sel[0])]
    field = region_field(body.faces.cpu().numpy(), regions.numpy(), len(REGIONS), iters)
    rid = torch.as_tensor(texel_regions(atlas, field))
    tex = table[rid]
    near = torch.as_tensor(atlas.texel_vertex)
    own = torch.as_tensor(face_part)[near]
    tex[own] = vertex[near[own]]
    return TexturedAlbedo(tex.reshape(size, size, 3).contiguous(), body.uv, body.uv_faces)


def boundary_jaggedness(labels: np.ndarray, a: int, b: int, sigma: float = 3.0, min_points: int = 12) -> float:
    """How far the boundary between regions ``a`` and ``b`` of a label image strays from its smoothed self.

    Args:
        labels: (H, W) int region of each pixel (e.g. a rendered region map; anything else, e.g.
            background, is another value).
        a, b: the two regions.
        sigma: the smoothing along the contour, in contour samples (about pixels).
        min_points: runs of the a|b boundary shorter than this are skipped.

    Returns:
        The mean distance in pixels between the a|b boundary points and their smoothed positions
        (NaN when no run is long enough).
    """
    from scipy.ndimage import binary_dilation, gaussian_filter1d
    from skimage.measure import find_contours

    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise InputError(f"labels: expected (H, W), got {labels.shape}")
    near_b = binary_dilation(labels == b, np.ones((3, 3), bool))
    devs = []
    for c in find_contours((labels == a).astype(np.float64), 0.5):
        r = np.clip(np.round(c).astype(int), 0, np.array(labels.shape) - 1)
        keep = near_b[r[:, 0], r[:, 1]] & binary_dilation(labels == a, np.ones((3, 3), bool))[r[:, 0], r[:, 1]]
        # Split into runs of consecutive boundary points between a and b.
        edges = np.flatnonzero(np.diff(np.concatenate([[0], keep.astype(int), [0]])))
        for s, e in zip(edges[::2], edges[1::2], strict=True):
            run = c[s:e]
            if len(run) < min_points:
                continue
            sm = gaussian_filter1d(run, sigma, axis=0, mode="nearest")
            inner = slice(int(2 * sigma), len(run) - int(2 * sigma))  # the ends are pulled inward by the filter
            if len(run[inner]):
                devs.append(np.linalg.norm(run[inner] - sm[inner], axis=1))
    return float(np.concatenate(devs).mean()) if devs else float("nan")
