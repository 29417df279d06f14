"""How much the real-photo round trip depends on the exact silhouette the estimator is given.

Run: ``.venv/bin/python benchmarks/bench_round_trip_mask.py --photos DIR --checkpoints shipped
train/checkpoints/X.pt [--erode -2 0 2 4]``

The round trip of ``relightnet evaluate photos`` (:func:`relightnet.pipeline.photo_checks.check_photo`):
each photo relit to six lights, the light estimated back from each relit photo. Here the estimate
is given the photo's person mask shrunk by k pixels (at the photo's resolution, ~1,024 px high;
k = 0 is the check itself, k < 0 grows it by -k), while the relighting keeps the mask as it is. A network that reads the
light from the silhouette's last pixels — where a photo relit with the network's own maps shows
exactly the shading it predicted — loses its round trip when the silhouette moves by a fraction
of a working-size pixel. Median over photos × lights of the scale-invariant irradiance error.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

from relightnet.model.photo_input import morph_mask  # noqa: E402
from relightnet.pipeline.photo_checks import check_photo, list_photos, load_photo, model_functions  # noqa: E402
from relightnet.segment import segment_person  # noqa: E402


def round_trip(photos: list, masks: list, checkpoint: str, erode: int) -> float:
    """Median round trip with the estimator's mask shrunk by ``erode`` pixels (grown where negative)."""
    relight, estimate = model_functions(None if checkpoint == "shipped" else checkpoint)

    def shrunk(image, mask):
        return estimate(image, morph_mask(mask > 0.5, -erode) if erode else mask)

    trips = []
    for image, mask in zip(photos, masks, strict=True):
        trips += list(check_photo(image, mask, relight, shrunk)["round_trip"].values())
    return statistics.median(trips)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--photos", required=True, help="a folder of photos of people")
    ap.add_argument("--checkpoints", nargs="+", default=["shipped"], help="'shipped' or checkpoint paths")
    ap.add_argument("--erode", nargs="+", type=int, default=[-2, 0, 2], help="pixels the estimator's mask is shrunk by "
                    "(negative: grown by)")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    photos = [load_photo(p)[0] for p in list_photos(args.photos)]
    masks = [(segment_person(im).mask > 0.5).float() for im in photos]
    rows = [[c, len(photos)] + [round_trip(photos, masks, c, k) for k in args.erode] for c in args.checkpoints]
    heads = [f"round trip, mask {'grown' if k < 0 else 'shrunk'} {abs(k)} px" if k else "round trip"
             for k in args.erode]
    print(table(["model", "photos"] + heads, rows))


if __name__ == "__main__":
    main()
