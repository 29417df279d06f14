"""Phone and stranger files a user report found: seeded families of variants, each asserting the right result.

Part of the resource cases (``resource_cases.CASES`` gathers them). Every family draws its variants
from its own fixed seed, so every run makes the same files:

* ``phone-width-*``: JPEG (4:2:0, 4:2:2, 4:4:4) and WebP photos of widths whose remainder mod 16 is
  1 to 4 and others, heights even and odd: relit to an RGB PNG (no alpha) of the photo's size.
* ``trunc-*``: a valid JPEG or PNG cut at 10 to 95 % of its bytes: one line naming it, no output.
* ``clip-vfr-*``, ``clip-late-*``: variable frame rate clips and a video stream that starts after its
  sound: the output's frames are shown at the input's times (within half a frame).
* ``hdr-*``: 10-bit HLG or PQ clips tagged BT.2020: the output is tagged BT.709.
* ``gray-*``: grayscale photos (mode L JPEG, grey RGB PNG) stay grey where the person is relit.
* ``icc-p3-*``: a photo with a Display-P3 profile: the relit PNG embeds that profile.
* ``light-*``: light files of 1e30, -1e30, NaN or negative everywhere: one line naming the light.
* ``out-is-input-*``: ``--out`` naming the input (its path, a hard link, a symbolic link): refused,
  the input's bytes unchanged.
"""

from __future__ import annotations

import io
import os
import sys
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from resource_runner import ROOT, Case  # noqa: E402

sys.path.pop(0)
if str(ROOT) not in sys.path:  # tests.io's clip and profile makers
    sys.path.append(str(ROOT))

RELIGHT = ["relight-image", "photo{}", "--mask", "mask.png", "--light", "studio", "--out", "out.png"]


def _case(name: str, doc: str, build: Callable[[Path], Case]) -> tuple[str, Callable[[Path], Case]]:
    """A named case whose docstring (shown by the benchmark's table) is ``doc``."""
    build.__doc__ = doc
    build.__name__ = build.__qualname__ = name.replace("-", "_").replace(".", "_")
    return name, build


def _picture(h: int, w: int, seed: int, gray: bool = False) -> np.ndarray:
    """(h, w, 3) uint8: a graded, noisy background with a brighter box for the person (a grey one if ``gray``)."""
    g = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w]
    img = np.stack([x * 150 // w + 40, y * 120 // h + 60, (x + y) * 90 // (h + w) + 80], -1)
    img = img + g.integers(-12, 13, (h, w, 3))
    img[h // 6:h * 5 // 6, w // 3:w * 2 // 3] += 50
    if gray:
        img = img.mean(-1, keepdims=True).repeat(3, -1)
    return img.clip(0, 255).astype(np.uint8)


def _mask(folder: Path, h: int, w: int) -> np.ndarray:
    """Write ``mask.png`` (the box of :func:`_picture`); (h, w) bool."""
    from PIL import Image

    m = np.zeros((h, w), np.uint8)
    m[h // 6:h * 5 // 6, w // 3:w * 2 // 3] = 255
    Image.fromarray(m).save(folder / "mask.png")
    return m > 0


def _out_image(folder: Path, name: str = "out.png"):
    from PIL import Image

    path = folder / name
    if not path.is_file():
        raise AssertionError(f"{name}: not written")
    im = Image.open(path)
    im.load()
    return im


# ---- 1. phone photos of every width ---------------------------------------------------------


def _width_family() -> dict:
    g = np.random.default_rng(1203)
    rems = [1, 2, 3, 4, 2, 4, 0, 7, 9, 15]
    kinds = [("jpeg", 2), ("jpeg", 1), ("jpeg", 0)] * 2 + [("jpeg", 2)] + [("webp", None)] * 3
    order = g.permutation(len(rems))
    cases = {}
    for i, j in enumerate(order):
        w = 16 * int(g.integers(5, 22)) + rems[j]
        h = int(g.integers(60, 260)) // 2 * 2 + (i % 2)
        fmt, sub = kinds[i]
        chroma = {2: "420", 1: "422", 0: "444", None: "420"}[sub]  # lossy WebP is 4:2:0
        name = f"phone-width-{w}x{h}-{chroma}-jpeg" if fmt == "jpeg" else f"phone-width-{w}x{h}-webp"

        def build(folder: Path, w=w, h=h, fmt=fmt, sub=sub, seed=i) -> Case:
            from PIL import Image

            im = Image.fromarray(_picture(h, w, seed))
            suffix = ".jpg" if fmt == "jpeg" else ".webp"
            if fmt == "jpeg":
                im.save(folder / f"photo{suffix}", quality=88, subsampling=sub)
            else:
                im.save(folder / f"photo{suffix}", quality=85)
            _mask(folder, h, w)

            def check(folder: Path) -> None:
                out = _out_image(folder)
                if out.mode != "RGB" or out.size != (w, h):
                    raise AssertionError(f"out.png: {out.mode} {out.size}; expected RGB {(w, h)} (the photo's)")

            return Case([a.format(suffix) for a in RELIGHT], f"photo{suffix}", expect="ok", outputs=("out.png",),
                        check=check)

        cases.update([_case(name, f"A {w} × {h} {fmt.upper()} photo ({chroma}): relit to an RGB PNG of its size.",
                            build)])
    return cases


# ---- 2. truncated photos --------------------------------------------------------------------


def _trunc_family() -> dict:
    g = np.random.default_rng(37)
    cases = {}
    for fmt in ("jpeg", "png"):
        for pct in list(dict.fromkeys(int(p) for p in g.uniform(10, 95, 8)))[:4]:
            def build(folder: Path, fmt=fmt, pct=pct) -> Case:
                from PIL import Image

                buf = io.BytesIO()
                Image.fromarray(_picture(180, 243, pct)).save(buf, "JPEG" if fmt == "jpeg" else "PNG")
                data = buf.getvalue()
                suffix = ".jpg" if fmt == "jpeg" else ".png"
                (folder / f"photo{suffix}").write_bytes(data[:len(data) * pct // 100])
                _mask(folder, 180, 243)
                return Case([a.format(suffix) for a in RELIGHT], f"photo{suffix}", check=_no_out)

            cases.update([_case(f"trunc-{fmt}-{pct}pct", f"A {fmt.upper()} photo cut at {pct} % of its bytes: "
                                "one line naming it, nothing written.", build)])
    return cases


def _no_out(folder: Path) -> None:
    if (folder / "out.png").exists() or (folder / "out.mp4").exists():
        raise AssertionError("an output was written by a run that failed")


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
    import av

    g = np.random.default_rng(seed)
    with av.open(str(path), "w") as c:
        s = c.add_stream("libx265", rate=10)
        s.width, s.height, s.pix_fmt = w, h, "yuv420p10le"
        s.options = {"x265-params": "bframes=0:log-level=error"}
        cc = s.codec_context
        cc.color_primaries, cc.color_trc, cc.colorspace, cc.color_range = 9, trc, 9, 1
        for i in range(n):
            y = g.integers(200, 500, (h, w)).astype(np.uint16)
            y[h // 6:h * 5 // 6, w // 3:w * 2 // 3] = 700
            planes = (y, np.full((h // 2, w // 2), 480, np.uint16), np.full((h // 2, w // 2), 540, np.uint16))
            f = av.VideoFrame(w, h, "yuv420p10le")
            for plane, a in zip(f.planes, planes, strict=True):
                buf = np.zeros((a.shape[0], plane.line_size // 2), np.uint16)
                buf[:, :a.shape[1]] = a
                plane.update(buf.tobytes())
            f.pts = i
            for p in s.encode(f):
                c.mux(p)
        for p in s.encode():
            c.mux(p)


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


# ---- 5. grayscale photos --------------------------------------------------------------------


def _gray_family() -> dict:
    g = np.random.default_rng(5)
    cases = {}
    for k, fmt in enumerate(("l-jpeg", "l-jpeg", "rgb-png", "rgb-png")):
        w, h = int(g.integers(90, 300)), int(g.integers(80, 260))

        def build(folder: Path, w=w, h=h, fmt=fmt, k=k) -> Case:
            from PIL import Image

            img = _picture(h, w, k, gray=True)
            suffix = ".jpg" if fmt == "l-jpeg" else ".png"
            if fmt == "l-jpeg":
                Image.fromarray(img[..., 0], "L").save(folder / "photo.jpg", quality=90)
            else:
                Image.fromarray(img).save(folder / "photo.png")
            person = _mask(folder, h, w)

            def check(folder: Path) -> None:
                out = np.asarray(_out_image(folder).convert("RGB")).astype(int)[person]
                spread = max(np.abs(out[:, 0] - out[:, 1]).max(), np.abs(out[:, 1] - out[:, 2]).max())
                if spread > 1:
                    raise AssertionError(f"out.png: the relit grey person has colour (max |R-G|, |G-B| = {spread})")

            return Case([a.format(suffix) for a in RELIGHT], f"photo{suffix}", expect="ok", outputs=("out.png",),
                        check=check)

        what = "mode L JPEG" if fmt == "l-jpeg" else "grey RGB PNG"
        cases.update([_case(f"gray-{fmt}-{w}x{h}", f"A {w} × {h} {what}: the relit person stays grey.", build)])
    return cases


# ---- 6. ICC profiles ------------------------------------------------------------------------


def _icc_family() -> dict:
    g = np.random.default_rng(3)
    cases = {}
    for fmt in ("jpeg", "png", "webp"):
        w, h = int(g.integers(70, 260)), int(g.integers(70, 260))

        def build(folder: Path, w=w, h=h, fmt=fmt) -> Case:
            from PIL import Image

            from tests.io.icc_profiles import display_p3

            icc = display_p3()
            suffix = {"jpeg": ".jpg", "png": ".png", "webp": ".webp"}[fmt]
            Image.fromarray(_picture(h, w, w)).save(folder / f"photo{suffix}", icc_profile=icc)
            _mask(folder, h, w)

            def check(folder: Path) -> None:
                got = _out_image(folder).info.get("icc_profile")
                if got != icc:
                    raise AssertionError(f"out.png: ICC profile {'missing' if got is None else 'changed'}; "
                                         "expected the photo's Display-P3 profile")

            return Case([a.format(suffix) for a in RELIGHT], f"photo{suffix}", expect="ok", outputs=("out.png",),
                        check=check)

        cases.update([_case(f"icc-p3-{fmt}-{w}x{h}", f"A {w} × {h} {fmt.upper()} photo with a Display-P3 profile: "
                            "the relit PNG embeds it.", build)])
    return cases


# ---- 7. absurd lights -----------------------------------------------------------------------


def _light_family() -> dict:
    import json

    def npz(sh):
        def write(path: Path) -> None:
            with open(path, "wb") as f:
                np.savez(f, sh=np.asarray(sh, np.float32))
        return write

    def js(text: str):
        return lambda path: path.write_text(text)

    g = np.random.default_rng(7)
    base = g.uniform(-0.5, 0.5, (9, 3))
    base[0] = 2.0
    big, nan = base.copy(), base.copy()
    big[int(g.integers(0, 9))] = 1e30
    nan[int(g.integers(1, 9)), int(g.integers(0, 3))] = np.nan
    neg = np.zeros((9, 3))
    neg[0] = -float(g.uniform(0.5, 3))

    def rows(a: np.ndarray) -> str:  # json writes NaN as the bare word, which Python's reader takes
        return json.dumps({"sh": a.tolist()})

    variants = {
        "light-npz-1e30": ("a light .npz with a coefficient of 1e30", ".npz", npz(big)),
        "light-npz-minus-1e30": ("a light .npz with a coefficient of -1e30", ".npz", npz(-big)),
        "light-json-1e30": ("a light .json with a coefficient of 1e30", ".json", js(rows(big))),
        "light-json-nan": ("a light .json with a NaN coefficient", ".json", js(rows(nan))),
        "light-npz-nan": ("a light .npz with a NaN coefficient", ".npz", npz(nan)),
        "light-npz-negative-everywhere": ("a light .npz whose irradiance is negative everywhere", ".npz", npz(neg)),
    }
    cases = {}
    for name, (what, suffix, write) in variants.items():
        def build(folder: Path, suffix=suffix, write=write) -> Case:
            from PIL import Image

            Image.fromarray(_picture(64, 64, 0)).save(folder / "photo.png")
            _mask(folder, 64, 64)
            write(folder / f"light{suffix}")
            argv = ["relight-image", "photo.png", "--mask", "mask.png", "--light", f"light{suffix}", "--out", "out.png"]
            return Case(argv, f"light{suffix}", check=_no_out)

        cases.update([_case(name, f"Relit under {what}: one line naming the light, nothing written.", build)])
    return cases


# ---- 8. the output is the input -------------------------------------------------------------


def _same_family() -> dict:
    def variant(name: str, doc: str, link: str | None, command: str):
        def build(folder: Path) -> Case:
            from PIL import Image

            Image.fromarray(_picture(64, 64, 8)).save(folder / "p.png")
            _mask(folder, 64, 64)
            before = (folder / "p.png").read_bytes()
            out, outputs = "p.png", ()
            if link == "hard":
                os.link(folder / "p.png", folder / "same.png")
                out = "same.png"
            elif link == "sym":
                os.symlink("p.png", folder / "same.png")
                out = "same.png"

            def check(folder: Path) -> None:
                if (folder / "p.png").read_bytes() != before:
                    raise AssertionError("p.png: the input was changed by a run that wrote its result over it")
                if link and not (folder / "same.png").exists():
                    raise AssertionError("same.png: the link to the input was removed")

            argv = ["relight-image", "p.png", "--mask", "mask.png", "--light", "studio", "--out", out]
            if command == "segment":
                argv = ["segment", "p.png", "--out", out]
            return Case(argv, out, outputs=outputs, check=check)

        return _case(name, doc, build)

    return dict([
        variant("out-is-input-relight", "relight-image with --out the photo itself: refused, the photo unchanged.",
                None, "relight"),
        variant("out-is-input-hard-link", "relight-image with --out a hard link to the photo: refused, unchanged.",
                "hard", "relight"),
        variant("out-is-input-symlink", "relight-image with --out a symbolic link to the photo: refused, unchanged.",
                "sym", "relight"),
        variant("out-is-input-segment", "segment with --out the photo itself: refused, the photo unchanged.",
                None, "segment"),
    ])


CASES = {**_width_family(), **_trunc_family(), **_clip_family(), **_hdr_family(), **_gray_family(),
         **_icc_family(), **_light_family(), **_same_family()}
#: The video families take more than a few seconds on a loaded machine.
SLOW = {n for n in CASES if n.startswith(("clip-", "hdr-"))}
