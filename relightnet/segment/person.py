"""A person's mask and body landmarks in one image, in two stages.

1. **Find** (:func:`find_person`): candidate square crops are the frame's square tiles (side:
   the frame's shorter side, half-overlapping along the longer one) and, around each person
   region that the selfie model finds in a tile, a crop of 1.25 × the region's longer side.
   The selfie model is made for people near the camera and loses hands and feet (on
   generated full-body people it often finds only pieces), so it only proposes crops.
2. **Segment** (:func:`segment_crop`): the full-body pose model reads an upright square crop,
   resized to 256² (outside the image the crop is black), and gives the person's presence
   probability, the mask (pasted back into the frame) and 33 landmarks. The candidate with
   the highest presence wins (the largest mask among near-equal ones); then the crop is taken
   around its own mask (1.25 × the box's longer side) and read again (``refine`` times), so
   the result no longer depends on where the candidate crop was.

In a video the crop of frame t comes from the mask of frame t − 1 (:mod:`.video`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from ..checks import InputError, check_shape
from .models import INPUT_SIZE, PersonModels, PoseOutput

__all__ = ["PersonMask", "CROP_SCALE", "candidate_crops", "find_person", "crop_around", "crop_pixels", "segment_crop",
           "refine_person", "segment_person", "mask_box"]

#: The pose model's crop: this many times the person box's longer side (MediaPipe's ROI scale).
CROP_SCALE = 1.25
#: A person region smaller than this fraction of the frame is noise, not a person.
MIN_AREA = 1e-3
#: Below this presence probability the pose model saw no person in its crop.
MIN_PRESENCE = 0.5
#: Candidates whose presence is this close to the best are ranked by mask area (largest person).
PRESENCE_TIE = 0.05


@dataclass(frozen=True, eq=False)
class PersonMask:
    """One person in one image.

    mask (H, W) float32 in {0, 1}; probability (H, W) in [0, 1] (zero outside the crop);
    crop (cx, cy, side): the square, in image pixels, that the pose model read;
    landmarks (33, 5): BlazePose's body points as x, y in image pixels, z in the same pixel
    scale (relative to the hips, negative toward the camera), visibility and presence
    probabilities; world (33, 3): the same points in metres around the hips (y down);
    score: probability that a person is in the crop.
    """

    mask: torch.Tensor
    probability: torch.Tensor
    crop: tuple[float, float, float]
    landmarks: torch.Tensor
    world: torch.Tensor
    score: float


def _check_image(image: torch.Tensor, name: str) -> tuple[int, int]:
    d = check_shape(image, [3, "H", "W"], name=name)
    if not image.is_floating_point():
        raise InputError(f"{name}: expected float sRGB in [0, 1], got {image.dtype}")
    return d["H"], d["W"]


def _to_input(x: torch.Tensor) -> np.ndarray:
    """(3, h, w) float -> (256, 256, 3) float32 numpy, area-averaged when shrinking."""
    x = F.interpolate(x[None].float(), size=(INPUT_SIZE, INPUT_SIZE), mode="bilinear", align_corners=False,
                      antialias=True)[0]
    return x.clamp(0, 1).permute(1, 2, 0).numpy()


def _largest_region(fg: np.ndarray) -> np.ndarray | None:
    """The largest 8-connected region of a boolean map (None when there is none)."""
    from scipy import ndimage

    labels, n = ndimage.label(fg, structure=np.ones((3, 3), bool))
    if n == 0:
        return None
    sizes = np.bincount(labels.ravel())[1:]
    return labels == (1 + int(sizes.argmax()))


def mask_box(mask: torch.Tensor) -> tuple[float, float, float, float] | None:
    """(x0, y0, x1, y1) pixel box of a (H, W) mask's pixels above 0.5 (x1, y1 exclusive); None if empty."""
    ys, xs = torch.nonzero(mask > 0.5, as_tuple=True)
    if len(xs) == 0:
        return None
    return float(xs.min()), float(ys.min()), float(xs.max() + 1), float(ys.max() + 1)


def crop_around(box: tuple[float, float, float, float], scale: float = CROP_SCALE) -> tuple[float, float, float]:
    """The pose model's square crop (cx, cy, side) around a (x0, y0, x1, y1) box."""
    x0, y0, x1, y1 = box
    return (x0 + x1) / 2, (y0 + y1) / 2, scale * max(x1 - x0, y1 - y0, 1.0)


def crop_pixels(crop: tuple[float, float, float]) -> tuple[int, int, int]:
    """(x0, y0, s): the whole pixels of a square crop (cx, cy, side) — its top-left corner and side
    (at least 2), before clipping to the image (:func:`segment_crop` reads them)."""
    cx, cy, side = crop
    s = max(int(round(side)), 2)
    return int(round(cx - s / 2)), int(round(cy - s / 2)), s


def _tiles(h: int, w: int) -> list[tuple[int, int, int]]:
    """(x0, y0, side) square tiles of side min(h, w), half-overlapping along the longer side."""
    side = min(h, w)
    n = math.ceil((max(h, w) - side) / (side / 2)) + 1
    offsets = [round(k * (max(h, w) - side) / max(n - 1, 1)) for k in range(n)]
    return [(o, 0, side) if w >= h else (0, o, side) for o in offsets]


def candidate_crops(image: torch.Tensor, models: PersonModels) -> list[tuple[float, float, float]]:
    """Stage 1: square crops (cx, cy, side) in image pixels where a person may be (module docstring)."""
    h, w = _check_image(image, "image")
    crops = []
    for x0, y0, side in _tiles(h, w):
        crops.append((x0 + side / 2, y0 + side / 2, float(side)))
        prob = models.selfie(_to_input(image[:, y0:y0 + side, x0:x0 + side]))
        region = _largest_region(prob > 0.5)
        if region is None or region.mean() < MIN_AREA:
            continue
        ys, xs = np.nonzero(region)
        k = side / INPUT_SIZE
        crops.append(crop_around((x0 + xs.min() * k, y0 + ys.min() * k, x0 + (xs.max() + 1) * k,
                                  y0 + (ys.max() + 1) * k)))
    return crops


def find_person(image: torch.Tensor, models: PersonModels) -> PersonMask | None:
    """Stages 1 and 2 once: the best candidate's :class:`PersonMask`, or None when no crop shows a person.

    The best is the most confident read whose mask has a region; among reads within
    :data:`PRESENCE_TIE` of it, the largest mask. The pose model reads every candidate, but a mask is
    made at the photo's resolution only for the reads that can win (most confident first).

    Args:
        image: (3, H, W) sRGB in [0, 1].
    """
    h, w = _check_image(image, "image")
    reads = [(i, *r) for i, r in enumerate(_read_crop(image, c, models) for c in candidate_crops(image, models))
             if r[1].presence >= MIN_PRESENCE]
    reads.sort(key=lambda r: -r[2].presence)  # stable: equal presences keep the candidates' order
    found: list[tuple[int, PersonMask]] = []
    for i, pixels, out in reads:
        if found and out.presence < found[0][1].score - PRESENCE_TIE:
            break  # no read from here on can be the best or tie with it
        res = _crop_result(h, w, pixels, out)
        if res is not None:
            found.append((i, res))
    if not found:
        return None
    best = found[0][1].score
    tied = [r for _, r in sorted(found, key=lambda f: f[0]) if r.score >= best - PRESENCE_TIE]
    return max(tied, key=lambda r: float(r.mask.sum()))  # the first of equal masks, in the candidates' order


def _square_crop(image: torch.Tensor, x0: int, y0: int, side: int) -> torch.Tensor:
    """(3, side, side) window of the image at (x0, y0), black where it leaves the image."""
    h, w = image.shape[1:]
    out = image.new_zeros(3, side, side)
    ix0, iy0, ix1, iy1 = max(x0, 0), max(y0, 0), min(x0 + side, w), min(y0 + side, h)
    if ix1 > ix0 and iy1 > iy0:
        out[:, iy0 - y0:iy1 - y0, ix0 - x0:ix1 - x0] = image[:, iy0:iy1, ix0:ix1]
    return out


def _read_crop(image: torch.Tensor, crop: tuple[float, float, float], models: PersonModels):
    """The pose model on one square crop: ``((x0, y0, side) whole pixels, PoseOutput)``."""
    x0, y0, s = crop_pixels(crop)
    return (x0, y0, s), models.pose(_to_input(_square_crop(image, x0, y0, s)))


def _crop_result(h: int, w: int, pixels: tuple[int, int, int], out: PoseOutput) -> PersonMask | None:
    """A pose read of the crop at ``pixels`` (x0, y0, side) as a :class:`PersonMask` of an (H, W) image,
    or None when it sees no person (its presence or its mask)."""
    x0, y0, s = pixels
    if out.presence < MIN_PRESENCE:
        return None
    # Logits are resized (not probabilities) so that the 0.5 outline is interpolated smoothly.
    ix0, iy0, ix1, iy1 = max(x0, 0), max(y0, 0), min(x0 + s, w), min(y0 + s, h)
    prob = torch.zeros(h, w)
    if ix1 > ix0 and iy1 > iy0:
        logits = F.interpolate(torch.from_numpy(out.mask_logits)[None, None], size=(s, s), mode="bilinear",
                               align_corners=False)[0, 0]
        prob[iy0:iy1, ix0:ix1] = torch.sigmoid(logits[iy0 - y0:iy1 - y0, ix0 - x0:ix1 - x0])
    region = _largest_region((prob > 0.5).numpy())
    if region is None:
        return None
    lm = torch.from_numpy(out.landmarks).float()
    k = s / INPUT_SIZE
    lm[:, 0] = x0 + lm[:, 0] * k
    lm[:, 1] = y0 + lm[:, 1] * k
    lm[:, 2] = lm[:, 2] * k
    return PersonMask(torch.from_numpy(region).float(), prob, (x0 + s / 2, y0 + s / 2, float(s)), lm,
                      torch.from_numpy(out.world).float(), out.presence)


def segment_crop(image: torch.Tensor, crop: tuple[float, float, float], models: PersonModels) -> PersonMask | None:
    """Stage 2: the person's mask and landmarks from the pose model on one square crop.

    Args:
        image: (3, H, W) sRGB in [0, 1].
        crop: (cx, cy, side) in image pixels (:func:`crop_around`).

    Returns:
        :class:`PersonMask` in image coordinates, or None when the model sees no person there.
    """
    h, w = _check_image(image, "image")
    return _crop_result(h, w, *_read_crop(image, crop, models))


def refine_person(image: torch.Tensor, res: PersonMask, models: PersonModels, times: int = 1) -> PersonMask:
    """Read the crop around ``res``'s own mask again, ``times`` times (keeps the last result that found the person)."""
    for _ in range(times):
        again = segment_crop(image, crop_around(mask_box(res.mask)), models)
        if again is None:
            break
        res = again
    return res


def segment_person(image: torch.Tensor, models: PersonModels | None = None, refine: int = 2,
                   name: str = "image") -> PersonMask:
    """The largest person's mask and landmarks in one image (both stages).

    Args:
        image: (3, H, W) sRGB in [0, 1] (any size).
        models: loaded :class:`PersonModels` (made here when None; pass one for many images).
        refine: how many more times the pose model reads a crop around its own mask.
        name: what the user calls the image (starts the error message).

    Returns:
        :class:`PersonMask` with (H, W) maps.

    Raises:
        InputError: ``"{name}: no person found"`` when there is none.
    """
    _check_image(image, name)
    models = models if models is not None else PersonModels()
    res = find_person(image, models)
    if res is None:
        raise InputError(f"{name}: no person found (expected a photo or frame showing a person)")
    return refine_person(image, res, models, refine)
