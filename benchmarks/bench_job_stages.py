"""Stage timings of ``relight-image`` and ``relight-video`` in one process (used by ``bench_jobs.py``).

Each stage is timed where the job calls it: the package's own functions are wrapped with a timer in
this process (nothing else changes), then the job runs as the command runs it.
"""

from __future__ import annotations

import contextlib
import time
from collections import defaultdict
from pathlib import Path

from common import table


class Timers:
    """Seconds spent per stage name, summed over calls."""

    def __init__(self) -> None:
        self.s: dict[str, float] = defaultdict(float)

    def wrap(self, name: str, fn):
        def timed(*a, **k):
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                self.s[name] += time.perf_counter() - t0
        return timed

    def wrap_iter(self, name: str, it):
        it = iter(it)
        while True:
            t0 = time.perf_counter()
            try:
                x = next(it)
            except StopIteration:
                self.s[name] += time.perf_counter() - t0
                return
            self.s[name] += time.perf_counter() - t0
            yield x


@contextlib.contextmanager
def patched(obj, name: str, value):
    old = getattr(obj, name)
    setattr(obj, name, value)
    try:
        yield
    finally:
        setattr(obj, name, old)


def _print(title: str, timers: Timers, total: float, order: list[str]) -> None:
    rows = [[k, timers.s[k], 100 * timers.s[k] / total] for k in order if k in timers.s]
    counted = sum(timers.s[k] for k in order if k in timers.s and not k.startswith("  "))  # "  ": a part of the above
    rows.append(["other (Python, checks, smoothing)", total - counted, 100 * (1 - counted / total)])
    rows.append(["total", total, 100.0])
    print(f"\n{title}\n")
    print(table(["stage", "s", "% of total"], rows))


def photo_stages(photo: Path, d: Path) -> None:
    """relight-image's stages (the code of ``relightnet._cli.relight.run``), the process warm."""
    import relightnet.io.image as image_io
    import relightnet.pipeline.relight_bands as rb
    from relightnet._cli.inputs import read_photo
    from relightnet.io import write_image
    from relightnet.light import preset_light
    from relightnet.pipeline.backends import make_predictor
    from relightnet.pipeline.relight_image import relight_image
    from relightnet.segment import sources

    timers = Timers()
    t0 = time.perf_counter()
    model = timers.wrap("start-up: load the CNN", make_predictor)("torch", None, "cpu")
    with patched(image_io, "_decode_pixels", timers.wrap("decode", image_io._decode_pixels)), \
            patched(sources, "segment_person", timers.wrap("segmentation", sources.segment_person)), \
            patched(type(model), "crop", timers.wrap("framing + CNN", type(model).crop)), \
            patched(rb, "photo_albedo_rows", timers.wrap("  of which: photo albedo", rb.photo_albedo_rows)), \
            patched(rb, "edge_matte", timers.wrap("soft edges: matte", rb.edge_matte)), \
            patched(rb, "soft_composite", timers.wrap("soft edges: composite", rb.soft_composite)), \
            patched(image_io, "_png_bytes", timers.wrap("encode PNG", image_io._png_bytes)):
        image, mask, alpha = read_photo(str(photo), None)
        t1 = time.perf_counter()
        res = relight_image(model, image, preset_light("sunset"), mask, maps=False, soft_edges=alpha is None)
        timers.s["relight: all bands (incl. photo albedo)"] = time.perf_counter() - t1 - timers.s["framing + CNN"] \
            - timers.s["soft edges: matte"] - timers.s["soft edges: composite"]
        write_image(d / "stage.png", res.image, srgb=False, alpha=alpha)
    total = time.perf_counter() - t0
    h, w = image.shape[1:]
    _print(f"relight-image stages, {photo.name} ({w}×{h}), warm process", timers, total,
           ["start-up: load the CNN", "decode", "segmentation", "framing + CNN",
            "relight: all bands (incl. photo albedo)", "  of which: photo albedo", "soft edges: matte",
            "soft edges: composite", "encode PNG"])


def video_stages(clip: Path, d: Path, label: str) -> None:
    """relight-video's stages (``relightnet.pipeline.relight_video.relight_video``), the process warm."""
    import importlib

    import relightnet.io as io_pkg

    rv = importlib.import_module("relightnet.pipeline.relight_video")  # the module (its function has its name)
    from relightnet.io import VideoWriter
    from relightnet.light import preset_light
    from relightnet.pipeline.backends import make_predictor
    from relightnet.segment import sources

    timers = Timers()
    model = make_predictor("torch", None, "cpu")
    read_video, track = io_pkg.read_video, sources.track_person
    with patched(io_pkg, "read_video", lambda p: timers.wrap_iter("decode", read_video(p))), \
            patched(sources, "track_person", lambda *a, **k: timers.wrap_iter("tracked", track(*a, **k))), \
            patched(type(model), "crop", timers.wrap("framing + CNN", type(model).crop)), \
            patched(rv, "relight_over_photo", timers.wrap("relight + composite (incl. soft edges)",
                                                          rv.relight_over_photo)), \
            patched(VideoWriter, "write", timers.wrap("encode", VideoWriter.write)), \
            patched(VideoWriter, "close", timers.wrap("encode", VideoWriter.close)):
        t0 = time.perf_counter()
        n = rv.relight_video(model, clip, None, preset_light("sunset"), d / "stages.mp4", progress=False)
        total = time.perf_counter() - t0
    timers.s["segmentation (tracked)"] = timers.s.pop("tracked") - timers.s["decode"]  # it pulls the frames
    _print(f"relight-video stages, {clip.name} {label}, {n} frames ({n / total:.2f} frames/s), warm process",
           timers, total, ["decode", "segmentation (tracked)", "framing + CNN",
                           "relight + composite (incl. soft edges)", "encode"])
