"""The app's cost per change of light at about 1 megapixel (target: ≤ 150 ms after a first pass ≤ 3 s).

Run: ``.venv/bin/python benchmarks/bench_app.py [--threads 2] [--side 1024]``

A generated person (the app's example, 256²) is scaled up to SIDE² (1 MP at 1024) and opened as
the app does (:func:`relightnet.app.load_photo`: decoding and the person segmentation), then:

- ``first pass``: :class:`relightnet.app.RelightSession` — the CNN once, the photo's albedo and the
  exposure reference;
- ``change of light``: :meth:`RelightSession.relight_u8` (the live view) for a new light in words
  each time (the words parsed and projected, T·L′ over the person's box, the exposure scale, the
  sRGB composite);
- ``+ PNG``: the same plus encoding the result as the page receives it (Gradio's PNG);
- ``exact``: :meth:`RelightSession.relight` (float, the sRGB curve computed; the download);
- ``relight-image``: the whole CLI computation for one light (:func:`relightnet.pipeline.relight_image`),
  for comparison.

Medians of 9 (first pass: 3) of the wall time and of the process's CPU time (all threads): on a
shared machine the wall time includes waiting for a core, the CPU time does not.
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

from relightnet.app import RelightSession, load_photo
from relightnet.app.examples import example_person  # noqa: E402
from relightnet.io import read_image, write_image  # noqa: E402
from relightnet.light import load_light  # noqa: E402
from relightnet.pipeline.backends import make_predictor  # noqa: E402
from relightnet.pipeline.relight_image import relight_image  # noqa: E402


def _median_ms(fn, repeat):
    """(median wall ms, median CPU ms of the process, all threads) of ``fn(i)`` for i < repeat."""
    wall, cpu = [], []
    for i in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn(i)
        wall.append((time.perf_counter() - t0) * 1e3)
        cpu.append((time.process_time() - c0) * 1e3)
    return statistics.median(wall), statistics.median(cpu)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--side", type=int, default=1024)
    ap.add_argument("--examples", default=os.path.join(tempfile.gettempdir(), "relightnet-bench-app"))
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    small = read_image(example_person(args.examples))
    big = torch.nn.functional.interpolate(small.permute(2, 0, 1)[None], size=(args.side, args.side),
                                          mode="bilinear", align_corners=False)[0].permute(1, 2, 0)
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "photo.png"
        write_image(path, big, srgb=False)
        photo = load_photo(path)
    predict = make_predictor()
    relighter = RelightSession(predict, photo)
    first = _median_ms(lambda i: RelightSession(predict, photo), 3)
    words = [f"key:az={-80 + 20 * i},el=30,size=20,power=3 + ambient:0.2" for i in range(9)]
    change = _median_ms(lambda i: relighter.relight_u8(load_light(words[i])), 9)
    exact = _median_ms(lambda i: relighter.relight(load_light(words[i])), 9)

    def with_png(i):
        import PIL.Image

        PIL.Image.fromarray(relighter.relight_u8(load_light(words[i])).numpy()).save(io.BytesIO(), format="png")

    png = _median_ms(with_png, 9)
    light = load_light(words[0])
    cli = _median_ms(lambda i: relight_image(predict, photo.image, light, photo.mask), 3)
    mp = args.side * args.side / 1e6
    print(f"{args.side}x{args.side} ({mp:.2f} MP), {args.threads} threads")
    rows = [["first pass (CNN, albedo, reference)", first], ["change of light (live view, uint8)", change],
            ["change of light + PNG encoding", png], ["change of light, exact sRGB, float (the download)", exact],
            ["relight-image (whole computation)", cli]]
    print(table(["step", "median wall ms", "median CPU ms (all threads)"], [[n, *v] for n, v in rows]))
    print(f"change of light / relight-image: {change[0] / cli[0]:.3f} (wall), {change[1] / cli[1]:.3f} (CPU)")


if __name__ == "__main__":
    main()
