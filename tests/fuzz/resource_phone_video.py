"""The video families of the phone and stranger files (``resource_phone.py`` has the photos and the rest).

Part of the resource cases (``resource_cases.CASES`` gathers them); each family's variants are
drawn from its own fixed seed:

* ``clip-vfr-*``, ``clip-late-*``: variable frame rate clips (steps of 1/30, 1/15 and 1/10 s) and a
  video stream that starts after its sound: the output's frames are shown at the input's times
  (within half of the shortest frame step).
* ``hdr-*``: 10-bit HLG or PQ clips tagged BT.2020: the output stream and its frames are tagged BT.709.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from resource_phone import _case  # noqa: E402
from resource_runner import Case  # noqa: E402

sys.path.pop(0)


# ---- 3. variable frame rate and late video streams ------------------------------------------


def _clip_family() -> dict:
    g = np.random.default_rng(30)
    cases = {}
    for k in range(2):
        steps = g.choice([1 / 30, 1 / 15, 1 / 10], size=9, p=[0.5, 0.35, 0.15])
        times = [0.0, *np.cumsum(steps).round(6).tolist()]
        cases.update([_clip_case(f"clip-vfr-{k}", times, [times[3]], "head" if k else "masks",
                                 "A clip of 10 frames at 30, 15 and 10 fps mixed")])
    start = round(float(g.uniform(0.3, 0.7)), 2)
    times = [start + i / 30 for i in range(6)]
    cases.update([_clip_case(f"clip-late-{start:.2f}s", times, [start], "masks",
                             f"A clip whose video starts {start} s after its sound")])
    return cases


def _clip_case(name: str, times: list[float], clicks: list[float], masks: str, what: str):
    def build(folder: Path) -> Case:
        from tests.io.timed_media import decoded_frame_times, write_masks, write_timed_clip

        write_timed_clip(folder / "clip.mp4", times, clicks)
        src = decoded_frame_times(folder / "clip.mp4")
        if masks == "masks":
            write_masks(folder / "masks", len(times))
            how = ["--masks", "masks"]
        else:
            how = ["--mask-source", "head"]

        def check(folder: Path) -> None:
            out = decoded_frame_times(folder / "out.mp4")
            half = float(np.diff(src).min()) / 2
            if len(out) != len(src) or np.abs(out - src).max() > half:
                raise AssertionError(f"out.mp4 frames shown at {out.round(4).tolist()}; the input's at "
                                     f"{src.round(4).tolist()} (within {half:.4f} s)")

        outputs = ("out.mp4", *(f"masks/{t:03d}.png" for t in range(len(times))))
        return Case(["-q", "relight-video", "clip.mp4", *how, "--light", "studio", "--out", "out.mp4"], "clip.mp4",
                    expect="ok", outputs=outputs, check=check)

    return _case(name, f"{what}, relit ({masks}): its frames are shown at the input's times.", build)


# ---- 4. HDR clips ---------------------------------------------------------------------------


def _hdr_clip(path: Path, w: int, h: int, trc: int, n: int, seed: int) -> None:
    """``n`` frames of 10-bit 4:2:0 HEVC tagged BT.2020 (primaries and matrix, limited range) and ``trc``."""
    from tests.io.hdr_media import write_hevc10

    g = np.random.default_rng(seed)

    def frames():
        for _ in range(n):
            y = g.integers(200, 500, (h, w)).astype(np.uint16)
            y[h // 6:h * 5 // 6, w // 3:w * 2 // 3] = 700
            yield y, np.full((h // 2, w // 2), 480, np.uint16), np.full((h // 2, w // 2), 540, np.uint16)

    write_hevc10(path, frames(), (w, h), trc)


def _hdr_family() -> dict:
    g = np.random.default_rng(2020)
    cases = {}
    for k, (label, trc) in enumerate((("hlg", 18), ("hlg", 18), ("pq", 16))):
        w, h = 16 * int(g.integers(4, 7)) + 2 * int(g.integers(0, 8)), 2 * int(g.integers(20, 40))

        def build(folder: Path, w=w, h=h, trc=trc, k=k) -> Case:
            import av

            from relightnet.io import write_image

            _hdr_clip(folder / "clip.mp4", w, h, trc, 3, k)
            (folder / "masks").mkdir()
            m = np.zeros((h, w, 3), np.uint8)
            m[h // 6:h * 5 // 6, w // 3:w * 2 // 3] = 255
            for t in range(3):
                write_image(folder / "masks" / f"{t:03d}.png", m)

            def check(folder: Path) -> None:
                with av.open(str(folder / "out.mp4")) as c:
                    cc = c.streams.video[0].codec_context
                    tags = (cc.color_primaries, cc.color_trc, cc.colorspace)
                    f = next(c.decode(video=0))
                    ftags = (f.color_primaries, f.color_trc, f.colorspace)
                if tags != (1, 1, 1) or ftags != (1, 1, 1):
                    raise AssertionError(f"out.mp4: tagged (primaries, trc, matrix) {tags}, frames {ftags}; "
                                         "expected BT.709 (1, 1, 1)")

            outputs = ("out.mp4", *(f"masks/{t:03d}.png" for t in range(3)))
            return Case(["-q", "relight-video", "clip.mp4", "--masks", "masks", "--light", "studio", "--out",
                         "out.mp4"], "clip.mp4", expect="ok", outputs=outputs, check=check)

        cases.update([_case(f"hdr-{label}-{w}x{h}-{k}", f"A 10-bit {label.upper()} BT.2020 clip of {w} × {h}: "
                            "relit and tagged BT.709.", build)])
    return cases


CASES = {**_clip_family(), **_hdr_family()}
#: The video cases take about 5 s each on a loaded 2-core machine.
SLOW = set(CASES)
