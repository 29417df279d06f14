"""Draw the README's picture of the generator's clothed people: ``docs/clothes.png``.

Run: ``.venv/bin/python tools/clothes_picture.py [--out docs/clothes.png] [--res 192]`` (ANNY_CACHE_DIR set by make).

Six people, one column each, each wearing a chosen mix of garment and hair meshes (the
seeds and choices below), rendered by the generator itself. Rows: the image over its
background (8-bit, as stored), the albedo (sRGB) and the transport's DC band (grey, 1 = the
unshadowed maximum π·Y₀), where cloth shadowing the body shows.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import torch

from relightnet.color import linear_to_srgb
from relightnet.data import SynthConfig, generate_sample
from relightnet.data.generate import prepare_assets
from relightnet.io import write_image

#: (upper, lower, head, hair) per column.
LOOKS = [("loose_top", "wide_trousers", "none", "long"), ("open_coat", "skirt", "hood", "volume"),
         ("jacket", "trousers", "hat", "volume"), ("dress", "none", "none", "long"),
         ("loose_top", "skirt", "hat", "long"), ("open_coat", "trousers", "none", "volume")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/clothes.png")
    ap.add_argument("--res", type=int, default=192)
    args = ap.parse_args()
    torch.set_num_threads(1)
    assets = prepare_assets()
    cols = []
    for k, (upper, lower, head, hair) in enumerate(LOOKS):
        probs = {"upper": {upper: 1}, "lower": {lower: 1}, "head": {head: 1}, "hair": {hair: 1}}
        cfg = SynthConfig(res=args.res, partial_crop_prob=0.0, garment_probs=probs, prt_reuse=1)
        a = generate_sample(cfg, "train", 10 * k + 1, assets).arrays
        dc = torch.from_numpy(a["transport"][..., 0] / (math.pi * 0.5 / math.sqrt(math.pi))).clamp(0, 1)
        rows = [torch.from_numpy(a["image_composite"]).float() / 255,
                linear_to_srgb(torch.from_numpy(a["albedo"]).clamp(0, 1)),
                dc[..., None].expand(-1, -1, 3)]
        cols.append(torch.cat(rows, 0))
    sheet = torch.cat(cols, 1)
    write_image(args.out, sheet, srgb=False)
    print(f"wrote {args.out}: {tuple(sheet.shape)}; mean {float(np.mean(sheet.numpy())):.3f}")


if __name__ == "__main__":
    main()
