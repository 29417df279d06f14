"""The light of a background plate against the true light, on generated backgrounds.

Run: ``.venv/bin/python benchmarks/bench_plate_light.py --data data/plate_bench [--make]``

``--make`` first generates the dataset with ``relightnet synth`` (the config below: 240 stills at
128², env-map lights only; the generator renders 60% of their backgrounds from the light's own
env map, rotated and scaled like the light — those are the plates whose true light is known).
For every such still, four estimates of the light are compared with the truth with the metric
of ``relightnet evaluate light`` (the scale-invariant irradiance error over the sphere and over
the camera-facing hemisphere, :func:`relightnet.sh.scale_invariant_light_error`):

- ``constant``: the truth's own l = 0 band (a direction-less light of the true colour);
- ``plate``: :func:`relightnet.light.plate_light` of the background, through an 8-bit sRGB round
  trip (as a photo), with the sample's camera intrinsics (``plate@60``: a centred 60° pinhole);
- ``person``: the shipped CNN on the composite (person over the background, its mask);
- ``both``: :func:`relightnet.light.combine_person_plate` of the two (the plate where its frame shows the
  light, the person elsewhere).

The families are the env maps (``night`` and ``sunrise`` are held out from the CNN's training).
The generator's plates are what its crop camera sees (a full-body framing: about 28° across), so a
second table measures plates of a normal lens (60°), rendered from the eight env maps at 12 turns
each by the generator's :func:`relightnet.data.backgrounds.envmap_background`, against the
constant light and the best any fill rule could do with a perfect up/down profile (``zonal
oracle``: the truth's m = 0 coefficients alone).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

from relightnet.color import linear_to_srgb, srgb_to_linear  # noqa: E402
from relightnet.light import combine_person_plate, plate_light
from relightnet.light.plate import plate_view
from relightnet.sh import scale_invariant_light_error  # noqa: E402

CONFIG = """seed: 25
res: 128
lmax: 2
n_dirs: 128
shard_size: 60
counts: {train: 160, val: 0, test: 80}
hdri_train: [city, courtyard, forest, interior, studio, sunset]
hdri_test: [night, sunrise]
light_mix: {hdri: 1.0}
partial_crop_prob: 0.0
"""
METHODS = ("constant", "plate", "plate@60", "person", "both")


def _make(data: Path) -> None:
    cfg = data.with_suffix(".yaml")
    cfg.write_text(CONFIG)
    subprocess.run([sys.executable, "-m", "relightnet", "-q", "synth", "--config", str(cfg), "--out", str(data),
                    "--workers", "2"], check=True)


def _estimates(data: Path) -> tuple[dict, list[str]]:
    from relightnet.data.dataset import SynthDataset
    from relightnet.pipeline.backends import make_predictor

    predict = make_predictor()
    est = {m: [] for m in ("truth", *METHODS)}
    families = []
    for split in ("train", "test"):
        ds = SynthDataset(data, split, fields=("image_composite", "mask", "light", "background"), cache_shards=1)
        for i in range(len(ds)):
            meta = ds.meta(i)
            meta = json.loads(meta) if isinstance(meta, str) else meta
            if not meta["background"].get("matches_light"):
                continue
            it = ds[i]
            truth = it["light"].double()
            plate = srgb_to_linear((linear_to_srgb(it["background"].permute(1, 2, 0).clamp(0, 1)) * 255).round() / 255)
            const = torch.zeros_like(truth)
            const[0] = truth[0]
            person = predict.light(it["image_composite"], it["mask"][0]).double()
            intr = meta["camera"]["intrinsics"]
            on_plate = plate_light(plate, 2, intrinsics=intr).double()
            view = plate_view(*plate.shape[:2], intrinsics=intr)
            for m, v in (("truth", truth), ("constant", const), ("plate", on_plate),
                         ("plate@60", plate_light(plate, 2, 60.0).double()), ("person", person),
                         ("both", combine_person_plate(person, on_plate, view).double())):
                est[m].append(v)
            families.append(meta["light"]["hdri"])
    return {k: torch.stack(v) for k, v in est.items()}, families


def _wide_plates(turns: int = 12, hfov: float = 60.0) -> list[list]:
    """Rows (family, n, constant, plate, zonal oracle): median errors over the sphere on 60° plates."""
    import math

    from relightnet.data.backgrounds import envmap_background
    from relightnet.light import preset_envmap, preset_names
    from relightnet.sh import project_envmap, rotate_sh
    from relightnet.sh.rotation import rotation_about_up

    res = 128
    f = 0.5 * res / math.tan(math.radians(hfov) / 2)
    out, allv = [], {k: [] for k in ("constant", "plate", "oracle")}
    for name in preset_names():
        env = preset_envmap(name)
        base = project_envmap(env.double(), 2)
        v = {k: [] for k in allv}
        for i in range(turns):
            q = rotation_about_up(2 * math.pi * i / turns, dtype=torch.float64).T  # L(ω) = env(q ω)
            truth = rotate_sh(base, q.T)
            bg = envmap_background(env, (f, f, res / 2, res / 2), res, q, math.pi, 1.0)
            bg = bg * (0.18 / float(bg.mean(-1).median()))  # exposed like a photo: highlights clip
            bg = srgb_to_linear((linear_to_srgb(bg.clamp(0, 1)) * 255).round() / 255)  # 8 bits
            const, zonal = torch.zeros_like(truth), torch.zeros_like(truth)
            const[0] = truth[0]
            zonal[[0, 2, 6]] = truth[[0, 2, 6]]
            for k, e in (("constant", const), ("plate", plate_light(bg, 2, hfov).double()), ("oracle", zonal)):
                v[k].append(float(scale_invariant_light_error(e, truth)))
                allv[k].append(v[k][-1])
        out.append([name, turns, *(float(torch.tensor(v[k]).median()) for k in v)])
    out.append(["all", len(allv["plate"]), *(float(torch.tensor(allv[k]).median()) for k in allv)])
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default="data/plate_bench", help="dataset folder (made with --make)")
    ap.add_argument("--make", action="store_true", help="generate the dataset first")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    data = Path(args.data)
    if args.make:
        _make(data)
    est, families = _estimates(data)
    errors = {m: scale_invariant_light_error(est[m], est["truth"]) for m in METHODS}
    hemi = {m: scale_invariant_light_error(est[m], est["truth"], hemisphere=True) for m in METHODS}
    rows = []
    for fam in [*sorted(set(families)), "all"]:
        sel = torch.tensor([fam in ("all", f) for f in families])
        row = [fam, int(sel.sum())]
        row += [f"{float(errors[m][sel].median()):.3f} / {float(hemi[m][sel].median()):.3f}" for m in METHODS]
        rows.append(row)
    print(f"plates with a known light: {len(families)} (median error over the sphere / camera hemisphere)")
    print(table(["family", "n", *METHODS], rows))
    e = {m: float(errors[m].median()) for m in METHODS}
    print(f"\nplate vs constant: {1 - e['plate'] / e['constant']:+.0%} lower median error; "
          f"both vs person: {1 - e['both'] / e['person']:+.0%}; both vs plate: {1 - e['both'] / e['plate']:+.0%}")
    wide = _wide_plates()
    print("\n60° plates of the eight env maps, 12 turns each (median error over the sphere)")
    print(table(["family", "n", "constant", "plate", "zonal oracle"], wide))
    print(f"\nplate vs constant on 60° plates: {1 - wide[-1][3] / wide[-1][2]:+.0%} lower median error "
          f"(the zonal oracle: {1 - wide[-1][4] / wide[-1][2]:+.0%})")


if __name__ == "__main__":
    main()
