"""Soft edges of a relit photo: the matte and the relit border against the truth, on generated people.

Run: ``.venv/bin/python benchmarks/bench_soft_edges.py [--people 6] [--timing]``

Each generated person (the package's generator, ``test`` split, 512 px) is placed over a real
photograph (scikit-image's, as the segmentation benchmark does) at 1024 × 768 with exact
fractional coverage: the linear render and its mask are resized premultiplied with an
antialiasing filter, and the photo is the blend in linear light, written to 8 bits. The same
person rendered from its own albedo and transport under a new light, blended over the same
background with the same coverage, is the true relit photo.

``relight-image``'s relight (:func:`relightnet.pipeline.relight_image`) is run with the true mask
(coverage > 1/2) and with the package's own segmentation, pasted with the mask (hard) or with the
soft matte (soft). Reported, over the border band (:func:`relightnet.segment.matte.border_band` of the
true mask at the photo's band radius):

- alpha MAE: the mask's and the matte's (:func:`relightnet.segment.soft_matte`) error against the coverage;
- relit MAE: the relit photo against the true relit photo, in 8-bit sRGB levels, after one gain
  fitted on the person's interior (``relight-image`` keeps the photo's exposure, the truth does not);
  the CNN's own error inside the person is in both columns, the edge's is the difference.

``--timing`` adds ``relight_image`` on one photo resized to 2808 × 1866 (5.2 MP), soft against hard.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "segment"))
from common import table  # noqa: E402
from people import BACKGROUNDS, background  # noqa: E402

from relightnet.color import linear_to_srgb, srgb_to_linear  # noqa: E402
from relightnet.light import load_light  # noqa: E402
from relightnet.model import load_model  # noqa: E402
from relightnet.pipeline import relight_image  # noqa: E402
from relightnet.raster import erode  # noqa: E402
from relightnet.segment import segment_person, soft_matte
from relightnet.segment.matte import band_radius, border_band  # noqa: E402

SIZE = (1024, 768)
LIGHTS = ("key:az=-70,el=10,power=3 + ambient:0.15", "key:az=70,el=10,power=3 + ambient:0.15")


def _resized(x: torch.Tensor, size: tuple[int, int]) -> torch.Tensor:
    return F.interpolate(x[None], size=size, mode="bilinear", align_corners=False, antialias=True)[0]


def scene(arrays: dict, light: torch.Tensor, bg_name: str, rng) -> tuple:
    """``(photo (3, H, W) uint8, coverage (H, W), truth (3, H, W) linear)``: the person under its own
    light and under ``light``, blended over a real background with the same fractional coverage."""
    img = torch.as_tensor(np.asarray(arrays["image"])).float()
    mask = torch.as_tensor(np.asarray(arrays["mask"])).float()
    new = torch.einsum("hwk,kc->hwc", torch.as_tensor(np.asarray(arrays["transport"])).float(), light)
    new = (torch.as_tensor(np.asarray(arrays["albedo"])).float() * new.clamp_min(0)) * mask[..., None]
    exposure = 0.18 / float(img[mask > 0.5].mean(-1).median().clamp_min(1e-4))
    ys, xs = torch.nonzero(mask > 0.5, as_tuple=True)
    crop = (slice(int(ys.min()), int(ys.max()) + 1), slice(int(xs.min()), int(xs.max()) + 1))
    h = int(round(rng.uniform(0.6, 0.9) * SIZE[0]))
    w = int(round((crop[1].stop - crop[1].start) * h / (crop[0].stop - crop[0].start)))
    y0 = int(round(rng.uniform(0.05, 0.95 - h / SIZE[0]) * SIZE[0]))
    x0 = int(round(rng.uniform(0.1, 0.9) * SIZE[1] - w / 2))
    x0 = min(max(x0, 0), SIZE[1] - w)
    cover = torch.zeros(SIZE)
    cover[y0:y0 + h, x0:x0 + w] = _resized(mask[crop][None], (h, w))[0].clamp(0, 1)
    back = srgb_to_linear(background(bg_name, SIZE))
    out = []
    for person in (img, new):  # premultiplied: the render times its coverage, resized with it
        pre = torch.zeros(3, *SIZE)
        pre[:, y0:y0 + h, x0:x0 + w] = _resized((person * mask[..., None] * exposure)[crop].permute(2, 0, 1), (h, w))
        out.append(pre.clamp_min(0) + (1 - cover) * back)
    photo = (linear_to_srgb(out[0].clamp(0, 1)) * 255).round().to(torch.uint8)
    return photo, cover, out[1]


def relit_error(relit: torch.Tensor, truth: torch.Tensor, cover: torch.Tensor, band: torch.Tensor) -> float:
    """Mean |relit − truth| over the band in 8-bit sRGB levels, one gain on the person's interior fitted first."""
    lin = srgb_to_linear(relit.permute(2, 0, 1))
    inner = erode((cover > 0.999).float()[None, None], 4)[0, 0] > 0.5
    gain = float((lin[:, inner] / truth[:, inner].clamp_min(1e-3)).median())
    back = truth * (1 - cover)  # the background's share of the truth: the gain is the person's only
    true = linear_to_srgb(((truth - back) * gain + back).clamp(0, 1))
    return float((relit.permute(2, 0, 1) - true).abs()[:, band].mean()) * 255


def measure(n_people: int, seed: int) -> list[list]:
    from relightnet.data import SynthConfig
    from relightnet.data.generate import assets_for, generate_sample

    assets, model, rng = assets_for(None), load_model(), np.random.default_rng(seed)
    rows = []
    for i in range(n_people):
        arrays = generate_sample(SynthConfig(res=512), "test", i, body=assets).arrays
        words = LIGHTS[i % 2]
        light = load_light(words)
        photo, cover, truth = scene(arrays, light, BACKGROUNDS[i % len(BACKGROUNDS)], rng)
        band = border_band((cover > 0.5).float(), band_radius(*SIZE))
        image = photo.float() / 255
        masks = {"true": (cover > 0.5).float()}
        try:
            masks["segmentation"] = segment_person(image).mask
        except ValueError:
            pass
        for source, mask in masks.items():
            alpha = soft_matte(photo, mask)
            hard = relight_image(model, image, light, mask, maps=False, soft_edges=False).image
            soft = relight_image(model, image, light, mask, maps=False).image
            rows.append([i, source, float((mask - cover)[band].abs().mean()), float((alpha - cover)[band].abs().mean()),
                         relit_error(hard, truth, cover, band), relit_error(soft, truth, cover, band)])
    return rows


def timing(repeat: int = 3) -> list[list]:
    """relight_image at 5.2 MP, soft edges against the binary paste (median seconds)."""
    from relightnet.data import SynthConfig
    from relightnet.data.generate import generate_sample

    arrays = generate_sample(SynthConfig(res=512), "test", 0).arrays
    photo, cover, _ = scene(arrays, load_light("studio"), "coffee", np.random.default_rng(0))
    image = _resized(photo.float() / 255, (1866, 2808)).clamp(0, 1)
    mask = (_resized(cover[None], (1866, 2808))[0] > 0.5).float()
    model, light = load_model(), load_light("sunset")
    out = []
    for soft in (False, True):
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            relight_image(model, image, light, mask, maps=False, soft_edges=soft)
            times.append(time.perf_counter() - t0)
        out.append(statistics.median(times))
    return [["relight_image 2808x1866", out[0], out[1], out[1] / out[0]]]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--people", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timing", action="store_true")
    args = ap.parse_args()
    rows = measure(args.people, args.seed)
    print(table(["person", "mask", "alpha MAE mask", "alpha MAE matte", "relit MAE hard (levels)",
                 "relit MAE soft (levels)"], rows))
    for source in ("true", "segmentation"):
        sel = [r for r in rows if r[1] == source]
        if sel:
            med = [statistics.median(r[k] for r in sel) for k in range(2, 6)]
            print(f"median, {source} mask: alpha MAE {med[0]:.3f} -> {med[1]:.3f}; relit MAE {med[2]:.2f} -> "
                  f"{med[3]:.2f} levels")
    if args.timing:
        print(table(["job", "hard (s)", "soft (s)", "soft / hard"], timing()))


if __name__ == "__main__":
    main()
