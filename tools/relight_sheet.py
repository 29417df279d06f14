"""A side-by-side sheet of relit photos: the photo, then each model's relight, with close-ups.

Run: ``.venv/bin/python tools/relight_sheet.py PHOTOS_DIR --before OLD.pt --hard-before --out sheet.jpg``

Every photo of the folder is relit as ``relight-image`` relights it (the package's segmentation,
exposure kept) under a white key light from the left (``key:az=-70,el=10,power=3 +
ambient:0.15``), once per column: ``--before`` (a checkpoint, pasted with a binary mask when
``--hard-before``) and the shipped model with soft edges. Each row shows the photos at 512 px high,
then three 160 px close-ups (photo, before, after, side by side): the darkest part of the person (where colour blotches
showed), a wrist (hands, from the segmentation's landmarks) and the top of the outline (hair and
the edge). Not run by ``make``: it draws the README's picture.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import torch
import torch.nn.functional as F

from relightnet.light import load_light
from relightnet.pipeline.backends import make_predictor
from relightnet.pipeline.photo_checks import list_photos, load_photo
from relightnet.pipeline.relight_image import relight_image
from relightnet.segment import segment_person

LIGHT = "key:az=-70,el=10,power=3 + ambient:0.15"
ROW, CLOSE = 512, 160
#: BlazePose's wrists (left, right).
WRISTS = (15, 16)


def _centres(image: torch.Tensor, res) -> list[tuple[int, int]]:
    """(y, x) of the person's darkest 64 px block, a wrist and the top of the outline."""
    mask = res.mask
    h, w = mask.shape
    lum = image.mean(0) * mask + (1 - mask)  # background counts as bright
    blur = F.avg_pool2d(lum[None, None], 31, stride=1, padding=15, count_include_pad=False)[0, 0]
    inside = F.avg_pool2d(mask[None, None], 31, stride=1, padding=15)[0, 0] > 0.95
    dark = torch.where(inside, blur, torch.full_like(blur, 9.0)).argmin()
    lm = res.landmarks
    wrist = max(WRISTS, key=lambda i: float(lm[i, 3]) if lm.shape[1] > 3 else 0.0)
    wy, wx = int(lm[wrist, 1].clamp(0, h - 1)), int(lm[wrist, 0].clamp(0, w - 1))
    ys, xs = torch.nonzero(mask > 0.5, as_tuple=True)
    top = int(ys.min())
    tx = int(xs[ys == top].float().mean())
    return [(int(dark // w), int(dark % w)), (wy, wx), (top + CLOSE // 3, tx)]


def _crop(img: torch.Tensor, centre: tuple[int, int], size: int) -> torch.Tensor:
    h, w = img.shape[1:]
    y = min(max(centre[0] - size // 2, 0), max(h - size, 0))
    x = min(max(centre[1] - size // 2, 0), max(w - size, 0))
    return img[:, y:y + size, x:x + size]


def _resize(img: torch.Tensor, height: int) -> torch.Tensor:
    w = max(1, round(img.shape[2] * height / img.shape[1]))
    return F.interpolate(img[None], size=(height, w), mode="area" if height < img.shape[1] else "nearest")[0]


def row(path: Path, columns: list) -> torch.Tensor:
    image, _ = load_photo(path)
    res = segment_person(image)
    light = load_light(LIGHT)
    images = [image] + [relight_image(model, image, light, res.mask, maps=False, soft_edges=soft).image.permute(2, 0, 1)
                        for model, soft in columns]
    centres = _centres(image, res)
    close = max(CLOSE, image.shape[1] // 6)  # the close-up's side on the photo, shown at CLOSE px
    full = torch.cat([_resize(x, ROW) for x in images], 2)
    groups = [torch.cat([_resize(_crop(x, c, close), CLOSE) for x in images], 2) for c in centres]
    ups = torch.cat([F.pad(g, (0, 8), value=1.0) for g in groups], 2)  # the three close-ups side by side
    width = max(full.shape[2], ups.shape[2])
    return torch.cat([F.pad(x, (0, width - x.shape[2], 0, 4), value=1.0) for x in (full, ups)], 1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("photos")
    ap.add_argument("--before", required=True, help="the earlier model's checkpoint")
    ap.add_argument("--hard-before", action="store_true", help="paste the earlier column with a binary mask")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    columns = [(make_predictor("torch", args.before, "cpu"), not args.hard_before),
               (make_predictor("torch", None, "cpu"), True)]
    rows = [row(p, columns) for p in list_photos(args.photos)]
    width = max(r.shape[2] for r in rows)
    sheet = torch.cat([F.pad(r, (0, width - r.shape[2], 0, 8), value=1.0) for r in rows], 1)
    from PIL import Image

    pixels = (sheet.permute(1, 2, 0).clamp(0, 1) * 255).round().to(torch.uint8).numpy()
    Image.fromarray(pixels).save(args.out, quality=85)


if __name__ == "__main__":
    main()
