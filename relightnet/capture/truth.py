"""Generated clips with exact truth, to evaluate a capture against.

:func:`turning_person` films bare Anny (no garment geometry) with a generated person's look
painted into Anny's UV layout (:func:`person_texture`, as the data generator paints it:
:func:`relightnet.data.textures.sample_outfit`, the outfit's regions, :func:`~relightnet.data.textures.paint_albedo`)
and a seeded phenotype of an unseen adult, standing in a mild pose (``apose`` by default)
and turning ``turns`` full circles about the vertical axis at a constant rate, feet on the
floor, at the origin in front of :func:`relightnet.raster.default_camera`. It is rendered with
its PRT (occlusion, ``n_dirs`` directions) under one SH light over a procedural background, as
:func:`relightnet.pipeline.motion_demo.walking_source` renders its source, and written as an
sRGB 8-bit x264 video with an exact mask video beside it (rendered alpha > 0.5, ffv1 gray).

The default camera looks along −z without a roll, so its frame has the world's axes: the
light returned (and given) is camera-relative and world-relative at once.

:func:`light_pair` gives two clearly different lights for a light-invariance test: one clip
filmed under each should give the same albedo.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, check_shape

__all__ = ["TruthClip", "turning_person", "turning_params", "person_texture", "light_pair", "truth_phenotype"]

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class TruthClip:
    """A generated clip and its truth.

    Attributes:
        video: the source video (.mp4, x264, sRGB 8-bit).
        masks: the person's exact masks (.mkv, gray; 255 where the rendered alpha > 0.5).
        texture: (S, S, 3) float32 linear-RGB true albedo in Anny's UV layout (row 0 = v = 1).
        light: (9, 3) the SH light of every frame (camera-relative = world for the default camera).
        params: the body parameters rendered, as :class:`~relightnet.body.AnnyBody` takes them:
            ``pose`` (T, J, 3), ``trans`` (T, 3), ``phenotype`` {name: float}.
        size: (H, W) of the frames.
    """

    video: Path
    masks: Path
    texture: torch.Tensor
    light: torch.Tensor
    params: dict
    size: tuple[int, int]


def truth_phenotype(seed: int) -> dict[str, float]:
    """A seeded adult phenotype: the generator's :func:`~relightnet.data.poses.sample_phenotype` (ages 0.75–1),
    its height redrawn in 0.2–0.4 (about 1.45–1.75 m), so the default camera frames the whole person."""
    from ..data.poses import sample_phenotype

    rng = np.random.default_rng([int(seed), 11])
    return {**sample_phenotype(rng, ages=(0.75, 1.0)), "height": float(rng.uniform(0.2, 0.4))}


def person_texture(body, seed: int, size: int = 512) -> torch.Tensor:
    """A generated person's look painted in Anny's UV layout, as the data generator paints it.

    Args:
        body: :class:`~relightnet.body.AnnyBody`. seed: draws the outfit. size: texture side S (≥ 8).

    Returns:
        (S, S, 3) float32 linear albedo in [ALBEDO_MIN, ALBEDO_MAX], row 0 = v = 1.
    """
    from ..body.albedo import region_labels
    from ..data.textures import paint_albedo, region_field, sample_outfit, texel_regions, uv_atlas

    atlas = uv_atlas(body, size)
    outfit = sample_outfit(np.random.default_rng(int(seed)))
    hair = "none" if outfit["hair"] is None else "short"
    labels = region_labels(body, outfit["sleeves"], outfit["legs"], hair, parts=atlas.parts)
    field = region_field(body.faces.cpu().numpy(), labels.numpy())
    return paint_albedo(atlas, field, outfit, texel_regions(atlas, field))


def light_pair() -> tuple[torch.Tensor, torch.Tensor]:
    """Two clearly different (9, 3) lights: a warm key from the camera's left and a cool key from its
    right, each over the same dim grey ambient."""
    from ..light import ambient_light, directional_light

    warm = torch.tensor([1.0, 0.8, 0.55])
    cool = torch.tensor([0.55, 0.75, 1.0])
    a = ambient_light(0.25) + directional_light(torch.tensor([-1.0, 0.5, 0.7]), 2.4 * warm)
    b = ambient_light(0.25) + directional_light(torch.tensor([1.0, 0.3, 0.6]), 2.4 * cool)
    return a, b


def turning_params(body, n_frames: int, turns: float = 1.0, pose: str = "apose", seed: int = 0) -> dict:
    """Body parameters of a person standing in preset ``pose`` and turning ``turns`` circles about +y.

    Returns:
        ``pose`` (T, J, 3) (the root turned by 2π·turns·t/T at frame t), ``trans`` (T, 3) zeros,
        ``phenotype`` (:func:`truth_phenotype` of ``seed``).
    """
    from ..body import pose_preset

    T = int(n_frames)
    p = body.pose_from_dict(pose_preset(pose), T).clone()
    angle = 2 * math.pi * float(turns) * torch.arange(T, dtype=p.dtype) / T
    p[:, body.joint_index("root")] = angle[:, None] * torch.tensor([0.0, 1.0, 0.0], dtype=p.dtype)
    return {"pose": p, "trans": torch.zeros(T, 3, dtype=p.dtype), "phenotype": truth_phenotype(seed)}


def _check_args(light, n_frames, size, texture_size, fps) -> tuple[torch.Tensor, tuple[int, int]]:
    light = torch.as_tensor(light, dtype=torch.float32)
    check_shape(light, [9, 3], name="light")
    if not torch.isfinite(light).all():
        raise InputError("light: expected finite SH coefficients")
    hw = (int(size), int(size)) if np.isscalar(size) else tuple(int(s) for s in size)
    if len(hw) != 2 or min(hw) < 16:
        raise InputError(f"size: expected (H, W) of at least 16 pixels, got {size!r}")
    if isinstance(n_frames, bool) or int(n_frames) != n_frames or n_frames < 2:
        raise InputError(f"n_frames: expected an integer >= 2, got {n_frames!r}")
    if int(texture_size) != texture_size or texture_size < 8 or not fps > 0:
        raise InputError(f"texture_size, fps: expected an integer >= 8 and fps > 0, got {texture_size!r}, {fps!r}")
    return light, hw


def turning_person(out_dir, body, light, n_frames: int = 48, size=(256, 256), seed: int = 0, turns: float = 1.0,
                   texture_size: int = 512, fps: float = 30.0, pose: str = "apose", n_dirs: int = 64) -> TruthClip:
    """Film a generated person turning in place (module docstring): ``source.mp4`` and ``masks.mkv``.

    Args:
        out_dir: folder to write into (made if missing). body: :class:`~relightnet.body.AnnyBody`.
        light: (9, 3) SH light of every frame. n_frames: T ≥ 2. size: (H, W) or a side (≥ 16).
        seed: draws the look, the phenotype and the background. turns: full circles over the clip.
        texture_size: side S of the true texture. fps: frame rate. pose: the standing preset.
        n_dirs: PRT directions.

    Returns:
        The :class:`TruthClip`.
    """
    from ..color import linear_to_srgb
    from ..data.backgrounds import procedural_background
    from ..io import VideoWriter
    from ..prt import PrtSettings
    from ..raster import default_camera
    from ..render.frame import TexturedAlbedo
    from ..render.jobs import render_body_frames

    light, (h, w) = _check_args(light, n_frames, size, texture_size, fps)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    tex = person_texture(body, seed, texture_size)
    params = turning_params(body, n_frames, turns, pose, seed)
    bg, _ = procedural_background(np.random.default_rng([int(seed), 5]), max(h, w), 0.25)
    frames = render_body_frames(body, params, light, TexturedAlbedo(tex, body.uv, body.uv_faces),
                                camera=default_camera((h, w)), n_frames=int(n_frames),
                                prt=PrtSettings(n_dirs=int(n_dirs)), visible_only=True)
    video, masks = out / "source.mp4", out / "masks.mkv"
    with VideoWriter(video, fps=fps) as v, VideoWriter(masks, fps=fps, gray=True) as m:
        for fr in frames:
            a = fr.render.alpha[0][..., None]
            img = fr.render.image[0] + bg[:h, :w] * (1 - a)
            v.write((linear_to_srgb(img.clamp(0, 1)) * 255).round().to(torch.uint8).numpy())
            m.write((a > 0.5).to(torch.uint8).mul(255).expand(h, w, 3).contiguous().numpy())
    log.info("truth clip: %d frames of %dx%d, %.2f turns, in %s", n_frames, h, w, turns, out)
    return TruthClip(video, masks, tex, light, params, (h, w))
