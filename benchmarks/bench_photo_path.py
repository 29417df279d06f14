"""How the light error of generated test people depends on the way their image reaches the network.

Run: ``.venv/bin/python benchmarks/bench_photo_path.py --data data/clothed --checkpoints shipped
train/checkpoints/X.pt [--n 300] [--hires data/hires512]``

Four inputs of the same test items, for every model: the render (the person alone) at the generator's
own framing — what the earlier stages trained on and what ``evaluate`` scored —, the composite (the person
over its background, the silhouette's pixels blended) at that framing, and both framed again around
their masks by :func:`relightnet.model.inference.frame_person` (the path of ``relight-image`` and
the video jobs). With ``--hires``, a dataset of the same recipe at a higher resolution (its test
split): its composites framed down to the working size, with torch's plain bilinear resampling and
with an antialiased one. Scale-invariant irradiance error, median (p90); the hybrid network's light,
and its light head alone.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

from relightnet.color import linear_to_srgb  # noqa: E402
from relightnet.data.dataset import SynthDataset  # noqa: E402
from relightnet.model import normalize_input  # noqa: E402
from relightnet.model.checkpoint import load_model  # noqa: E402
from relightnet.model.inference import crop_to_box, frame_person  # noqa: E402
from relightnet.sh.metrics import scale_invariant_light_error  # noqa: E402


def _inputs(it: dict, size: int) -> dict:
    """The four network inputs (1, 4, s, s) of one item (module docstring)."""
    m = it["mask"][0].float()
    render = linear_to_srgb(it["image"].float().clamp(0, 1))
    comp = it["image_composite"].float() / 255
    out = {}
    for name, srgb in (("render", render), ("composite", comp)):
        out[f"{name}, own framing"] = normalize_input(srgb[None], m[None])
        x, mk, _ = frame_person(srgb, m, size)
        out[f"{name}, framed by frame_person"] = normalize_input(x, mk)
    return out


def _framed_down(it: dict, size: int, antialias: bool) -> torch.Tensor:
    m = it["mask"][0].float()
    comp = it["image_composite"].float() / 255
    x, mk, box = frame_person(comp, m, size)
    if antialias and box.size > size:
        x = torch.nn.functional.interpolate(crop_to_box(comp[None], box), size=(size, size), mode="bilinear",
                                            align_corners=False, antialias=True)
    return normalize_input(x, mk)


def _score(errs: dict, name: str, p, light: torch.Tensor) -> None:
    """Add a prediction's light error (and its light head's) to ``errs[name]``."""
    light_errs, head_errs = errs.setdefault(name, ([], []))
    light_errs.append(float(scale_invariant_light_error(p.light[0], light)))
    if p.light_head is not None:
        head_errs.append(float(scale_invariant_light_error(p.light_head[0], light)))


def _stats(errors: list[float]) -> str:
    e = np.array(errors)
    return f"{np.median(e):.3f} ({np.quantile(e, 0.9):.3f})"


@torch.no_grad()
def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True, help="dataset of stills (its test split)")
    ap.add_argument("--checkpoints", nargs="+", default=["shipped"], help="'shipped' or checkpoint paths")
    ap.add_argument("--n", type=int, default=300, help="test items")
    ap.add_argument("--hires", help="a dataset of the same recipe at a higher resolution (its test split)")
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    fields = ("image", "image_composite", "mask", "light")
    ds = SynthDataset(args.data, "test", fields=fields, cache_shards=1)
    hires = SynthDataset(args.hires, "test", fields=fields, cache_shards=1) if args.hires else None
    rows = []
    for c in args.checkpoints:
        model = load_model(None if c == "shipped" else c).eval()
        size = model.config.input_size
        errs: dict = {}
        for i in range(min(args.n, len(ds))):
            it = ds[i]
            for name, x in _inputs(it, size).items():
                _score(errs, name, model(x), it["light"])
        for i in range(min(args.n, len(hires))) if hires is not None else ():
            it = hires[i]
            for aa in (False, True):
                name = f"composite at {it['image'].shape[-1]}², framed down{', antialiased' if aa else ''}"
                _score(errs, name, model(_framed_down(it, size, aa)), it["light"])
        for name, (light, head) in errs.items():
            rows.append([c, name, len(light), _stats(light), _stats(head) if head else "–"])
    print(table(["model", "input", "n", "light error median (p90)", "light head alone"], rows))


if __name__ == "__main__":
    main()
