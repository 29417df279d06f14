"""Capture a fitted person: the frames streamed through :func:`~relightnet.capture.texture.frame_samples`,
fused, filled, and made a :class:`~relightnet.capture.avatar_file.CapturedAvatar`.

Only the texture's accumulators grow with the resolution; nothing grows with the clip's length
(the frames, masks and poses are consumed one at a time).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterable
from dataclasses import dataclass

import torch

from ..checks import InputError, check_shape
from .avatar_file import CapturedAvatar
from .fill import fill_unseen, mirror_texels
from .metrics import seen_share
from .offsets import apply_offsets
from .texture import TextureFusion, TextureOptions, frame_samples, texel_table

logger = logging.getLogger(__name__)

__all__ = ["CaptureResult", "capture_person"]

#: Frames posed together (the whole mesh, ~1 MB a frame).
_POSE_CHUNK = 8


@dataclass(frozen=True, eq=False)
class CaptureResult:
    """What :func:`capture_person` returns.

    Attributes:
        avatar: the :class:`~relightnet.capture.avatar_file.CapturedAvatar`.
        raw_texture: (S, S, 3) the frames' colours fused the same way without de-lighting (when asked),
            unfilled; else None.
        seen: (S, S) bool texels seen in some frame.
        ms_per_frame: wall time of the capture per frame (after the fit and the lights).
    """

    avatar: CapturedAvatar
    raw_texture: torch.Tensor | None
    seen: torch.Tensor
    ms_per_frame: float


def _posed(result, fb, offsets: torch.Tensor | None):
    """(verts (V, 3), normals (V, 3), faces) of every frame of the fit, in its view space."""
    from ..body.base import vertex_normals
    from ..fit.preview import fit_meshes

    T = result.pose.shape[0]
    for a in range(0, T, _POSE_CHUNK):
        out = fit_meshes(result, fb, a, min(a + _POSE_CHUNK, T))
        v, n = out.verts, out.normals
        if offsets is not None:
            v = apply_offsets(v, n, offsets)
            n = vertex_normals(v, out.faces)
        for i in range(v.shape[0]):
            yield v[i], n[i], out.faces


def _texture(values: torch.Tensor, table, fill: float = 0.0) -> torch.Tensor:
    """(M, C) island values → (S, S, C) texture, gutters copying their nearest island texel."""
    S = table.size
    full = torch.full((S * S, values.shape[1]), fill, dtype=values.dtype).index_copy_(0, table.index, values)
    return full[table.source].view(S, S, -1)


def capture_person(result, fb, frames: Iterable[torch.Tensor], masks: Iterable[torch.Tensor | None],
                   lights: torch.Tensor, offsets: torch.Tensor | None = None,
                   options: TextureOptions = TextureOptions(), raw: bool = False, atlas=None) -> CaptureResult:
    """Capture the albedo texture of a fitted person (module docstring of :mod:`.texture`).

    Args:
        result: the :class:`~relightnet.fit.FitResult` (view space, T frames of ``result.size``).
        fb: its :class:`~relightnet.fit.FitBody`.
        frames: T (3, H, W) sRGB frames in [0, 1], in order (an iterator: streamed).
        masks: T (H, W) bool person masks (None or empty: the frame adds nothing).
        lights: (T, K, 3) each frame's light, camera-relative, on the light estimate's scale.
        offsets: (V,) offsets along the normal (:func:`~relightnet.capture.offsets.solve_offsets`), or None.
        options: :class:`~relightnet.capture.texture.TextureOptions`.
        raw: also fuse the raw colours (:attr:`CaptureResult.raw_texture`).
        atlas: the body's :func:`~relightnet.data.textures.uv_atlas` at ``options.size`` (made when None).

    Raises:
        InputError: no frame saw the person.
    """
    from ..color import srgb_to_linear
    from ..data.textures import uv_atlas
    from ..fit.preview import fit_camera

    T = result.pose.shape[0]
    check_shape(lights, [T, "K", 3], name="lights")
    atlas = uv_atlas(fb.body, options.size) if atlas is None else atlas
    table = texel_table(atlas, fb.body.faces.cpu())
    fusion = TextureFusion(table.index.numel(), options.top_k, raw)
    camera = fit_camera(result)
    t0, used, t = time.perf_counter(), 0, -1
    with torch.no_grad():
        for t, ((v, n, faces), img, mask) in enumerate(zip(_posed(result, fb, offsets), frames, masks, strict=False)):
            if mask is None or bool(result.interpolated[t]) or not bool(mask.any()):
                continue
            s = frame_samples(table, v, n, faces, lights[t], camera, srgb_to_linear(img.clamp(0, 1)), mask.bool(),
                              options)
            if s is not None:
                fusion.add(s)
                used += 1
    if used == 0:
        raise InputError("capture: no frame shows the fitted person (expected frames with a person in them)")
    if t + 1 != T:
        raise InputError(f"capture: {t + 1} frames or masks for a fit of {T} frames")
    ms = 1e3 * (time.perf_counter() - t0) / max(t + 1, 1)
    return _finish(fusion, table, atlas, fb, result, offsets, used, ms, raw)


def _finish(fusion: TextureFusion, table, atlas, fb, result, offsets, used: int, ms: float, raw: bool
            ) -> CaptureResult:
    """Fill the unseen texels and make the :class:`CaptureResult`."""
    seen = fusion.total > 1e-3
    values = fusion.result("albedo")
    mirror = torch.as_tensor(mirror_texels(atlas.texel_pos[table.index.numpy()]))
    filled, how = fill_unseen(values, seen, table.tri, table.bary, mirror, fb.body.faces.cpu(),
                              torch.as_tensor(atlas.parts), fb.body.num_verts)
    seen_full = torch.zeros(table.size ** 2, dtype=torch.bool).index_copy_(0, table.index, seen)
    share = seen_share(seen_full.view(table.size, table.size), atlas)
    logger.info("capture: %d frame(s), %.0f ms a frame; %.1f%% of the surface seen, %.1f%% from the mirror "
                "image, %.1f%% inpainted", used, ms, 100 * share, 100 * float((how == 1).float().mean()),
                100 * float((how == 2).float().mean()))
    V = fb.body.num_verts
    avatar = CapturedAvatar(
        texture=_texture(filled, table).clamp(0, 1),
        confidence=_texture(fusion.total[:, None], table)[..., 0],
        filled=_texture(how[:, None].float(), table, 2.0)[..., 0].to(torch.int8),
        offsets=torch.zeros(V) if offsets is None else offsets.detach().float().cpu(),
        phenotype=result.phenotype.detach().float().cpu().reshape(6), seen_share=share, frames=used)
    raw_tex = _texture(fusion.result("raw"), table) if raw else None
    return CaptureResult(avatar, raw_tex, seen_full.view(table.size, table.size), ms)
