"""The synthetic sample generator: exact ground truth by construction.

``generate_sample(cfg, split, index)`` makes one still, ``generate_sequence(...)`` one clip;
both are pure functions of ``(cfg, split, index)`` (bit for bit, for a given torch thread
count): every random axis draws from its own child of :func:`~relightnet.data.config.sample_seed`
(body, pose, view, albedo, light, background, prt, noise), so changing how one axis draws
does not change the others. A clip uses child 100 of the sample's seed sequence, so clip
``i`` and still ``i`` are independent.

Geometry. The posed Anny mesh (feet on y = 0, turned by a random yaw) is moved into the
frame of a camera at a random distance, height and lateral offset, pitched toward the body
(± a few degrees): ``v_cam = R_x(pitch) (v − eye)``. Everything — PRT, rendering, normals,
light — is then in that camera frame, whose camera has rotation I, so the light frame of
the sample *is* the camera's (x toward the camera, y image right, z up in the image; the
world's up is tilted from z by the pitch). The square crop
(:func:`~relightnet.data.framing.crop_camera`) only changes the intrinsics.

Arrays (H = W = ``cfg.res``; float32 linear unless stated):

- ``transport`` (H, W, K): per-vertex PRT (``refined_transport``: occlusion by ray casting,
  ``cfg.n_dirs`` directions of a Fibonacci set randomly rotated per sample; the midpoints of
  the garments' subdivided outer sides are ray cast at shadow edges only) interpolated
  with the rasterizer's perspective-correct barycentrics. Only the vertices of faces that a
  pixel of the group's views shows are ray cast (the views are drawn and rasterized first);
  their rows equal those of casting every vertex, bit for bit. With a bounce (probability
  ``cfg.bounce_prob``, ``meta["flags"]["bounce"]``) it includes one interreflection off
  *grey* reflectors (each vertex's mean RGB albedo), so transport stays scalar (H, W, K).
- ``transport_unoccluded`` (H, W, K): the same quadrature with ``occlusion=False``,
  ``Σ_d max(n·ω_d, 0) Y(ω_d) w_d`` per vertex, interpolated. The same directions make
  ``transport[..., 0] ≤ transport_unoccluded[..., 0]`` exact without bounce. It differs
  from the closed form ``Â_l Y_k(n̂)`` at the pixel normal by the quadrature error of
  ``n_dirs`` directions and by interpolating a non-linear function of n (tests bound both).
- ``light`` (K, 3): the SH light in the camera's light frame. ``image`` = ``albedo`` ⊙
  (``transport`` · ``light``) on the mask, exactly up to float rounding, unless
  ``meta["flags"]["noise_std"] > 0``: then Gaussian noise of that std was added in the mask.
- ``albedo`` (H, W, 3) in [0.02, 0.9], 0 on background; ``mask`` (H, W) in {0, 1};
- ``normals`` (H, W, 3): unit, in the light frame of the camera, 0 on background;
- ``depth`` (H, W): distance in front of the camera (−z_view, metres), 0 on background;
- ``parts`` (H, W) uint8: 0 background, 1 + index into ``REGIONS`` (skin, hair, top, bottom, shoes),
  the arg-max of the smoothed region field at the pixel (the same edges as the albedo texture);
- ``image_srgb`` (H, W, 3) uint8: ``to_uint8(image)`` (sRGB, clipped: the light is normalised,
  :mod:`relightnet.data.lights`, so no exposure is applied);
- ``background`` (H, W, 3) linear and ``image_composite`` (H, W, 3) uint8 sRGB: the person over
  the background (:mod:`relightnet.data.backgrounds`), silhouette edges antialiased.

Precomputation: the UV atlas and region labels of the body model
(:func:`~relightnet.data.sample.prepare_assets`). Pass the :class:`SynthAssets` as ``body``;
a plain :class:`~relightnet.body.AnnyBody` also works (its assets are kept in a weak-keyed
module dict, :func:`~relightnet.data.sample.assets_for`); ``body=None`` builds everything on
every call (slow).
"""

from __future__ import annotations

import numpy as np

from ..checks import InputError
from .config import SynthConfig, sample_seed
from .render_sample import CLIP_KEY, render_clip, render_group
from .sample import GENERATOR_VERSION, TEXTURE_SIZE, Sample, SynthAssets, assets_for, prepare_assets

__all__ = ["GENERATOR_VERSION", "TEXTURE_SIZE", "Sample", "SynthAssets", "prepare_assets",
           "generate_sample", "generate_samples", "generate_sequence"]


def generate_sample(cfg: SynthConfig, split: str, index: int, body=None) -> Sample:
    """Generate still ``index`` of ``split`` (module docstring for the arrays and metadata).

    Args:
        cfg: the :class:`~relightnet.data.SynthConfig`.
        split: ``"train"``, ``"val"`` or ``"test"`` (test uses only ``cfg.hdri_test`` maps).
        index: sample index ≥ 0.
        body: None, an :class:`~relightnet.body.AnnyBody`, or :class:`SynthAssets` (fastest).

    Returns:
        :class:`Sample` with (H, W, ·) arrays and JSON-serialisable metadata.
    """
    ss = sample_seed(cfg, split, index)
    return render_clip(cfg, split, int(index), ss, assets_for(body), n_frames=None)


def generate_samples(cfg: SynthConfig, split: str, indices, body=None) -> list[Sample]:
    """Generate several stills, each group's person and PRT computed once (``cfg.prt_reuse``).

    The same samples as :func:`generate_sample` of each index, faster when ``indices`` hold
    whole groups (consecutive indices g·G … g·G + G − 1).

    Args:
        cfg, split, body: as :func:`generate_sample`. indices: ascending sample indices ≥ 0.

    Returns:
        A list of :class:`Sample`, one per index.
    """
    idx = [int(i) for i in indices]
    for i in idx:
        sample_seed(cfg, split, i)  # validates
    if any(b < a for a, b in zip(idx, idx[1:], strict=False)):
        raise InputError(f"indices: expected ascending sample indices, got {idx}")
    return render_group(cfg, split, idx, assets_for(body))


def generate_sequence(cfg: SynthConfig, split: str, index: int, n_frames: int, body=None) -> Sample:
    """Generate clip ``index`` of ``split``: one body and motion, fixed framing, a moving light.

    The light turns smoothly about the up axis (up to ±60°/s, or not at all) and ramps in
    level; with probability 0.3 it switches to another drawn light at a random frame
    (``meta["switch_frames"]``). The framing contains every frame; the background is static.

    Args:
        cfg, split, index, body: as :func:`generate_sample`.
        n_frames: T ≥ 1.

    Returns:
        :class:`Sample` whose arrays have a leading T axis (``light`` is (T, K, 3)).
    """
    ss = sample_seed(cfg, split, index)
    if isinstance(n_frames, bool) or not isinstance(n_frames, int | np.integer) or n_frames < 1:
        raise InputError(f"n_frames: expected an integer >= 1, got {n_frames!r}")
    child = np.random.SeedSequence(ss.entropy, spawn_key=(CLIP_KEY,))
    return render_clip(cfg, split, int(index), child, assets_for(body), n_frames=int(n_frames))
