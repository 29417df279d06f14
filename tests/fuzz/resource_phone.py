"""Phone and stranger files a user report found: seeded families of variants, each asserting the right result.

Part of the resource cases (``resource_cases.CASES`` gathers them). Every family draws its variants
from its own fixed seed, so every run makes the same files:

* ``phone-width-*``: JPEG (4:2:0, 4:2:2, 4:4:4) and WebP photos of widths whose remainder mod 16 is
  1 to 4 and others, heights even and odd: relit to an RGB PNG (no alpha) of the photo's size.
* ``trunc-*``: a valid JPEG or PNG cut at 10 to 95 % of its bytes: one line naming it, no output.
* ``clip-vfr-*``, ``clip-late-*``, ``hdr-*``: the video families, in ``resource_phone_video.py``.
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


CASES = {**_width_family(), **_trunc_family(), **_gray_family(), **_icc_family(), **_light_family(),
         **_same_family()}
#: (Each photo case takes a few seconds: none is slow.)
SLOW: set[str] = set()
