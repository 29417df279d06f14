"""A clean plate of a target video (the scene without its person) and where that person stood.

:func:`clean_plate` builds the background of a video from its frames and person masks:

1. **Samples.** At most ``max_samples`` frames, evenly spaced over the video, are kept,
   streamed into one preallocated uint8 (S, H, W, 3) buffer, so memory is bounded whatever the
   video's length (about S · H · W · 4 bytes with the masks: 400 MB for 48 samples at 1080p).
2. **Covered.** Each mask is dilated by ``margin`` pixels (the segmentation's outline is
   soft, and the person's contact shadow and motion blur lie just outside it) as it arrives,
   into one preallocated (S, H, W) bool buffer.
3. **Temporal median.** Per pixel and channel, the median of the samples where the dilated
   mask does not cover the pixel (the lower median for an even count). A pixel the person
   covers in some frames and uncovers in others gets only background samples.
4. **Inpainting.** Pixels covered in every sample have no background sample. They are
   filled by push–pull interpolation (Gortler et al. 1996): the known plate is averaged
   down a pyramid of halved resolutions (weights count known pixels) until every cell has
   a value, then each level's holes are filled from the bilinearly upsampled coarser level.
   The fill is a smooth blend of the surrounding background, without texture; those
   pixels are *flagged* (``CleanPlate.flagged``) and their share of the area the person
   ever covered is reported (``inpainted_share``); above :data:`WARN_SHARE` the avatar job
   warns in one line.

:func:`person_placement` reads the same masks for where the person stood: the median over
the samples of the feet (the figure's centre column, the mask's lowest row) and of the height
(box height) in pixels, each over the masks the frame's edges do not cut (:func:`person_box`).
:func:`placed_camera` turns that into the avatar's camera: the default camera's orientation
(so the camera-relative light is unchanged) moved so that the avatar's feet at the world
origin land on the person's feet and its standing height on the person's height. :func:`stand_in`
also tracks the person's box in every frame and moves the avatar along that path
(:mod:`.person_path`). The median needs a fixed camera: :func:`check_camera_start` (the first frames) and
:func:`stand_in` (the samples) refuse one that moves (:mod:`.camera_motion`); a pan is not registered.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from ..checks import InputError, check_shape
from ..raster import Camera, look_at, perspective_camera
from .camera_motion import EARLY_FRAMES, check_fixed_camera, thumbnail

logger = logging.getLogger(__name__)

__all__ = ["WARN_SHARE", "CleanPlate", "sample_indices", "dilate_masks", "masked_median", "push_pull_fill",
           "clean_plate", "Placement", "person_box", "person_placement", "placed_camera", "plate_psnr",
           "check_stand_in", "check_camera_start", "stand_in", "stand_in_frames"]

#: The avatar job warns when more than this share of the person's area had to be inpainted.
WARN_SHARE = 0.02
#: Rows of the median computed at once (bounds the float working memory).
_ROWS = 32


@dataclass(frozen=True, eq=False)
class CleanPlate:
    """A video's background.

    Attributes:
        plate: (H, W, 3) uint8 sRGB background.
        flagged: (H, W) bool pixels never uncovered in the samples (inpainted).
        covered: (H, W) bool pixels the (dilated) person covered in at least one sample.
        samples: (H, W) int64 number of background samples behind each pixel's median.
        inpainted_share: flagged pixels / covered pixels (0 when the person covered nothing).
        n_samples: frames sampled.
    """

    plate: np.ndarray
    flagged: np.ndarray
    covered: np.ndarray
    samples: np.ndarray
    inpainted_share: float
    n_samples: int


def sample_indices(n_frames: int, max_samples: int) -> list[int]:
    """Up to ``max_samples`` frame indices evenly spread over ``n_frames`` (all of them when fewer)."""
    if n_frames < 1 or max_samples < 1:
        raise InputError(f"clean plate: need n_frames >= 1 and max_samples >= 1, got {n_frames}, {max_samples}")
    if n_frames <= max_samples:
        return list(range(n_frames))
    return sorted({int(round(i * (n_frames - 1) / (max_samples - 1))) for i in range(max_samples)})


def dilate_masks(masks: torch.Tensor, margin: int) -> torch.Tensor:
    """(N, H, W) bool masks grown by ``margin`` pixels (a square structuring element)."""
    check_shape(masks, ["N", "H", "W"], name="masks")
    if margin <= 0:
        return masks.bool()
    k = 2 * int(margin) + 1
    return F.max_pool2d(masks[:, None].float(), k, stride=1, padding=int(margin))[:, 0] > 0


def masked_median(frames: torch.Tensor, covered: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Per-pixel temporal median over the uncovered samples, :data:`_ROWS` rows at a time (the float
    working memory is N × _ROWS × W × C, not the whole stack's).

    Args:
        frames: (N, H, W, C) uint8 or float samples.
        covered: (N, H, W) bool, True where the sample shows the person.

    Returns:
        ((H, W, C) float32 median, NaN where every sample is covered; (H, W) int64 uncovered counts).
    """
    d = check_shape(frames, ["N", "H", "W", "C"], name="frames")
    check_shape(covered, [d["N"], d["H"], d["W"]], name="covered")
    out = torch.empty(d["H"], d["W"], d["C"])
    count = torch.empty(d["H"], d["W"], dtype=torch.int64)
    for r in range(0, d["H"], _ROWS):
        x = frames[:, r:r + _ROWS].float()
        c = covered[:, r:r + _ROWS]
        x[c] = float("nan")
        out[r:r + _ROWS] = torch.nanmedian(x, dim=0).values
        count[r:r + _ROWS] = c.shape[0] - c.sum(0)
    return out, count


def push_pull_fill(image: torch.Tensor, known: torch.Tensor) -> torch.Tensor:
    """Fill the unknown pixels of an image by push–pull interpolation (module docstring, step 4).

    Args:
        image: (H, W, C) float values (anything where ``known`` is False).
        known: (H, W) bool.

    Returns:
        (H, W, C): ``image`` where known, the pyramid's interpolation elsewhere.
    """
    d = check_shape(image, ["H", "W", "C"], name="image")
    check_shape(known, [d["H"], d["W"]], name="known")
    if not bool(known.any()):
        raise InputError("push-pull fill: no known pixel to fill from")
    w = known.float()[None, None]
    x = torch.where(known[..., None], image, torch.zeros(())).permute(2, 0, 1)[None] * w
    levels = [(x, w)]
    while bool((levels[-1][1] <= 0).any()) and min(levels[-1][1].shape[-2:]) > 1:
        x, w = levels[-1]
        levels.append((F.avg_pool2d(x, 2, ceil_mode=True) * 4, F.avg_pool2d(w, 2, ceil_mode=True) * 4))
    x, w = levels[-1]
    val = x / w.clamp_min(1e-12)
    for x, w in reversed(levels[:-1]):
        up = F.interpolate(val, size=x.shape[-2:], mode="bilinear", align_corners=False)
        a = w.clamp(0, 1)
        val = a * (x / w.clamp_min(1e-12)) + (1 - a) * up
    out = val[0].permute(1, 2, 0)
    return torch.where(known[..., None], image, out)


def _sample(t: int, f, m) -> tuple[np.ndarray, torch.Tensor]:
    """One sample's checked (H, W, 3) uint8 frame and (H, W) bool mask."""
    f = np.asarray(f)
    if f.ndim != 3 or f.shape[2] != 3 or f.dtype != np.uint8:
        raise InputError(f"clean plate: frame {t}: expected (H, W, 3) uint8, got {f.shape} {f.dtype}")
    m = torch.as_tensor(np.asarray(m)) > 0.5
    if tuple(m.shape) != f.shape[:2]:
        raise InputError(f"clean plate: frame {t}: mask {tuple(m.shape)} differs from the frame {f.shape[:2]}")
    return f, m


def _stream_samples(frames: Iterable, want: set[int], margin: int | None) -> tuple[torch.Tensor, torch.Tensor]:
    """The sampled frames streamed into one preallocated (S, H, W, 3) uint8 buffer and their dilated masks
    into one (S, H, W) bool buffer (allocated at the first sample's size): (frames, covered), cut to the
    samples the iterator gave."""
    buf = cov = None
    k = 0
    for t, (f, m) in enumerate(frames):
        if t not in want:
            continue
        f, m = _sample(t, f, m)
        if buf is None:
            H, W = f.shape[:2]
            margin = max(2, round(0.01 * H)) if margin is None else int(margin)
            buf = torch.empty(len(want), H, W, 3, dtype=torch.uint8)
            cov = torch.empty(len(want), H, W, dtype=torch.bool)
        elif f.shape[:2] != tuple(buf.shape[1:3]):
            raise InputError(f"clean plate: frame {t}: size {f.shape[:2]} differs from the first sample's "
                             f"{tuple(buf.shape[1:3])}")
        buf[k] = torch.from_numpy(f)
        cov[k] = dilate_masks(m[None], margin)[0]  # one mask at a time: no float copy of the stack
        k += 1
    if buf is None:
        raise InputError("clean plate: the video has no frame")
    return buf[:k], cov[:k]


def clean_plate(frames: Iterable, n_frames: int, max_samples: int = 48, margin: int | None = None) -> CleanPlate:
    """The clean plate of a video from its frames and person masks (module docstring).

    Peak memory: about the samples' own, S · H · W · 4 bytes (module docstring, steps 1–3), plus a few frames.

    Args:
        frames: (frame, mask) pairs in the video's order (an iterator is read once): (H, W, 3) uint8
            frames and the person's (H, W) masks (values > 0.5 = person).
        n_frames: the video's frame count (to spread the samples).
        max_samples: frames kept for the median.
        margin: mask dilation in pixels (default: 1 % of the frame height, at least 2).

    Returns:
        :class:`CleanPlate`.
    """
    fs, covered = _stream_samples(frames, set(sample_indices(n_frames, max_samples)), margin)
    med, count = masked_median(fs, covered)
    flagged = count == 0
    ever = covered.any(0)
    if bool(flagged.all()):
        raise InputError("clean plate: the person covers the whole frame in every sample")
    filled = push_pull_fill(med, ~flagged) if bool(flagged.any()) else med
    plate = filled.round().clamp(0, 255).to(torch.uint8).numpy()
    share = float(flagged.sum()) / max(int(ever.sum()), 1)
    return CleanPlate(plate, flagged.numpy(), ever.numpy(), count.numpy(), share, len(fs))


@dataclass(frozen=True)
class Placement:
    """Where the person stood: ``feet`` (u, v) pixel of the feet (columns right, rows down), ``height`` in pixels."""

    feet: tuple[float, float]
    height: float


def person_box(m: np.ndarray, framed: bool = True) -> tuple[float, float, float] | None:
    """(feet u, feet v, height) of one (H, W) bool mask, or None when it is (nearly) empty. With ``framed``,
    a value the frame's edges cut is NaN: all three when the mask touches the left or right edge (part of
    the person is outside: what shows may be an arm or a leg), the height when it touches the top or
    bottom edge, v when it touches the bottom."""
    rows = np.nonzero(m.any(1))[0]
    if len(rows) < 4:
        return None
    top, bottom = rows[0], rows[-1]
    cols = np.nonzero(m)[1]  # the whole figure's centre column: the lowest rows show one foot mid-stride
    u, v, h = float(cols.mean()) + 0.5, float(bottom) + 1.0, float(bottom - top + 1)
    if not framed:
        return u, v, h
    if m[:, 0].any() or m[:, -1].any():
        return math.nan, math.nan, math.nan
    floor = bottom == m.shape[0] - 1
    return u, math.nan if floor else v, math.nan if top == 0 or floor else h


def person_placement(masks: Iterable) -> Placement | None:
    """The median feet position and height of a person over (H, W) masks (None when every mask is empty),
    each over the masks the frame's edges do not cut (:func:`person_box`), or over all when every one is cut."""
    ms = [np.asarray(m) > 0.5 for m in masks]
    return _placement([(person_box(m), person_box(m, framed=False)) for m in ms])


def _placement(boxes) -> Placement | None:
    """:func:`person_placement` from each mask's (framed, unframed) :func:`person_box` (no mask kept)."""
    framed = [b for b, _ in boxes if b is not None]
    if not framed:
        return None
    a = np.asarray(framed)
    cut = np.isnan(a).all(0)
    if cut.any():  # cut in every frame (a close-up): the cut values
        a[:, cut] = np.asarray([u for b, u in boxes if b is not None])[:, cut]
    med = np.nanmedian(a, axis=0)
    return Placement((float(med[0]), float(med[1])), float(med[2]))


def placed_camera(size, placement: Placement, body_height: float, fov_deg: float = 35.0) -> Camera:
    """A camera looking along −z (as :func:`~relightnet.raster.default_camera`) placed so that a body of
    ``body_height`` metres standing at the world origin has its feet at ``placement.feet`` and spans
    ``placement.height`` pixels. ``size``: (H, W)."""
    H, W = int(size[0]), int(size[1])
    if not (placement.height > 0 and body_height > 0):
        raise InputError(f"placement: expected positive heights, got {placement.height} px, {body_height} m")
    f = (H / 2) / math.tan(math.radians(fov_deg) / 2)
    ez = f * body_height / placement.height
    ex = (W / 2 - placement.feet[0]) * ez / f
    ey = (placement.feet[1] - H / 2) * ez / f
    eye = torch.tensor([ex, ey, ez], dtype=torch.float32)
    view = look_at(eye, eye - torch.tensor([0.0, 0.0, 1.0]))
    return perspective_camera(view, (H, W), fov_deg=fov_deg, near=max(0.05, ez / 20), far=ez * 20 + 10)


def plate_psnr(plate: np.ndarray, truth: np.ndarray, region: np.ndarray) -> float:
    """PSNR in dB of an (H, W, 3) uint8 plate against the true background over an (H, W) bool region."""
    region = np.asarray(region, dtype=bool)
    if not region.any():
        raise InputError("plate PSNR: the region is empty")
    d = plate.astype(np.float64)[region] - truth.astype(np.float64)[region]
    mse = float((d**2).mean())
    return math.inf if mse == 0 else 10 * math.log10(255.0**2 / mse)


def _stand_in_masks(target, target_masks, mask_source):
    """The target's frames with the person's masks for ``--replace-person`` (``head`` gives none: refused)."""
    from ..segment.sources import video_masks

    if target_masks is None and mask_source == "head":
        raise InputError("--replace-person: needs the person's masks: give --target-masks or use --mask-source "
                         "segment")
    return video_masks(target, target_masks, mask_source, allow_empty=True)


def _uint8(img: torch.Tensor) -> np.ndarray:
    """A (3, H, W) float sRGB frame in [0, 1] as (H, W, 3) uint8."""
    return (img.permute(1, 2, 0) * 255).round().to(torch.uint8).numpy()


def check_camera_start(target, target_masks=None, mask_source: str = "segment",
                       n_frames: int = EARLY_FRAMES) -> None:
    """``--replace-person``'s early check: refuse a target whose camera moves over its first ``n_frames``
    frames (the person's masks left out; :func:`.camera_motion.check_fixed_camera`), before any expensive
    work. ``target_masks``, ``mask_source``: as :func:`stand_in`."""
    info, _, frames = _stand_in_masks(target, target_masks, mask_source)
    thumbs, idx = [], []
    for t, img, m in frames:
        if t >= n_frames:
            break
        thumbs.append(thumbnail(_uint8(img), m))
        idx.append(t)
    if thumbs:
        check_fixed_camera(target, thumbs, idx, info.size[1])


def stand_in(target, out, n_frames: int, body, target_masks=None, mask_source: str = "segment",
             max_samples: int = 48, fov_deg: float = 35.0) -> tuple[CleanPlate, Camera, torch.Tensor]:
    """``avatar --replace-person``: the target's clean plate, the camera that puts the avatar where the
    person stood in the median frame (module docstring) and the avatar's path that follows the person
    frame by frame (:mod:`.person_path`). Writes ``OUT.plate.png`` (the plate) beside ``out``. A camera
    that moves between the plate's samples is refused before the median (:mod:`.camera_motion`).

    Args:
        target: the target video. out: the avatar's output path. n_frames: frames the avatar job writes.
        body: the avatar's body model (its standing height). target_masks, mask_source: the person's
            masks (:func:`relightnet.segment.sources.video_masks`; ``head`` gives none and is refused).

    Returns:
        (:class:`CleanPlate`, :class:`~relightnet.raster.Camera`, (T, 3) root offsets in metres,
        :func:`.person_path.path_offsets`).
    """
    from pathlib import Path

    from ..io import write_image
    from .person_path import path_offsets, smooth_track

    info, _, frames = _stand_in_masks(target, target_masks, mask_source)
    want = set(sample_indices(n_frames, max_samples))
    kept, boxes, thumbs, idx = [], [], [], []

    def pairs():  # one decode: the frames come back from the masks' iterator
        for t, img, m in frames:
            if t >= n_frames:
                break
            m = torch.as_tensor(m) > 0.5
            boxes.append(person_box(m.numpy()))
            f = _uint8(img)
            if t in want:  # the boxes and a thumbnail only: no mask kept beyond the plate's buffer
                kept.append((boxes[-1], person_box(m.numpy(), framed=False)))
                thumbs.append(thumbnail(f, m.numpy()))
                idx.append(t)
            yield f, m
        if thumbs:  # before the median: a moving camera would only smear it
            check_fixed_camera(target, thumbs, idx, info.size[1])

    plate = clean_plate(pairs(), n_frames, max_samples)
    where = _placement(kept)
    if where is None:
        raise InputError(f"--replace-person: {target}: no person found in any sampled frame")
    level = logging.WARNING if plate.inpainted_share > WARN_SHARE else logging.INFO
    logger.log(level, "%s: %.1f%% of the person's area was never uncovered and is inpainted in the clean plate%s",
               target, 100 * plate.inpainted_share,
               " (the person does not move enough to reveal the background)" if level == logging.WARNING else "")
    out = Path(out)
    write_image(out.with_name(out.stem + ".plate.png"), torch.from_numpy(plate.plate).float() / 255, srgb=False)
    with torch.no_grad():
        rest = body().verts[0]
    height = float(rest[:, 1].max() - rest[:, 1].min())
    camera = placed_camera(info.size, where, height, fov_deg)
    track = smooth_track(boxes, (*where.feet, where.height))
    return plate, camera, path_offsets(info.size, where, track, height, fov_deg)


def check_stand_in(replace_person: bool, plate, camera) -> None:
    """``--replace-person`` makes its own plate and camera: refuse it with ``plate`` or ``camera``."""
    if replace_person and (plate is not None or camera is not None):
        raise InputError("--replace-person builds the plate and places the camera itself: drop --plate / --camera")


def stand_in_frames(target, out, n_frames: int, body, target_masks=None, mask_source: str = "segment",
                    params: dict | None = None):
    """:func:`stand_in` for the avatar job: (the plate repeated as the frames to composite over, the camera,
    the motion's parameters ``params`` with the root moved along the person's path every frame)."""
    import itertools

    plate, camera, offsets = stand_in(target, out, n_frames, body, target_masks, mask_source)
    params = {} if params is None else params
    trans = params.get("trans")
    trans = torch.zeros(n_frames, 3) if trans is None else torch.as_tensor(trans)
    return itertools.repeat(plate.plate), camera, {**params, "trans": trans + offsets[:len(trans)].to(trans)}
