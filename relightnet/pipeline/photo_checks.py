"""Two checks of the 2D path on real photos of people, with no ground truth (``relightnet evaluate photos``).

A folder of photos is all they need: each photo's person is found by the package's own person
segmentation (:func:`relightnet.segment.segment_person`, the full-resolution mask > 0.5), and a
photo taller than ``max_height`` (1,024 px by default) is first shrunk to that height (area
average, aspect kept); everything below runs on the shrunk photo. Photos are decoded by the
bounded image reader (:func:`relightnet.io.read_image`: the ``--max-pixels`` limit).

**Side contrast** (does a light from one side light that side?). The photo is relit
(:func:`relightnet.pipeline.relight_image` with its defaults, as ``relightnet relight-image``
does: the photo's own albedo, the exposure kept) under L_left = 3·Y(d_left) + 0.3 on the l = 0
coefficient (white; :func:`relightnet.light.side_light`), d_left = (0.5, −0.85, 0.2) normalised, and under
L_right, the same with d_right = (0.5, +0.85, 0.2). In the camera-relative light frame
(docs/design.md, "Frames"; :mod:`relightnet.sh.frames`) x points to the camera, y to the
image's right and z up, so d_left (y < 0) comes from the image's left, a little in front and
above. The person is split at the mask's horizontal centroid (its mean pixel column, not the
middle of its box) into image-left and image-right halves, and each half's mean linear
luminance (Rec. 709 weights on linear RGB) is taken (:func:`side_means`)::

    side contrast = (left / right under L_left) / (left / right under L_right)

1 for a relighter that ignores the light; a Lambertian sphere gives 12.7 (its shading under the
two lights, albedo ½, the mask its disc); the target for a person is ≥ 4.

**Round trip** (does the relit photo carry the light it was relit with?). The photo is relit
to each light of :func:`check_lights` (the two side lights, a light from above and three
shipped presets) and the light is estimated back from the relit photo (sRGB floats, not
quantised to 8 bits) with the estimator ``relightnet estimate-light`` uses
(:meth:`~relightnet.pipeline.backends.Predictor.light`) and the photo's own mask (the person
has not moved); the estimate is scored against the light with the scale-invariant irradiance
error of ``evaluate light`` (:func:`relightnet.sh.scale_invariant_light_error`, whole sphere;
0 is perfect, 1 no better than a zero light). The "changes nothing" baseline scores the light
estimated from the original photo against each light. Medians are over photos × lights.

**Colour** (does relighting invent colour?): the photo relit under a white key light from either
side, its chroma shift p99 and fine-scale chroma energy ratio against the photo
(:mod:`relightnet.pipeline.photo_colour`), the worse of the two lights per photo.
"""

from __future__ import annotations

import math
import os
import statistics
from collections.abc import Callable
from pathlib import Path

import torch
import torch.nn.functional as F

from ..checks import InputError, check_shape, sh_order_from_count
from ..color import luminance, srgb_to_linear
from ..io import PHOTO_SUFFIXES
from ..light import light_from_words, preset_light, side_light
from ..sh import resize_sh, scale_invariant_light_error
from .backends import as_predictor, make_predictor
from .photo_colour import COLOUR_LIGHTS, colour_figures
from .relight_image import relight_image

__all__ = ["SIDE_LEFT", "SIDE_RIGHT", "FROM_ABOVE", "ROUND_TRIP_PRESETS", "MAX_HEIGHT", "side_light", "check_lights",
           "side_means", "side_contrast", "model_functions", "load_photo", "list_photos", "check_photo",
           "photo_checks", "format_photo_report", "write_photo_report"]

#: Direction (light frame) of the side light from the image's left: y < 0 is the image's left.
SIDE_LEFT = (0.5, -0.85, 0.2)
#: Direction of the side light from the image's right.
SIDE_RIGHT = (0.5, 0.85, 0.2)
#: Direction of the round trip's light from above (a little toward the camera).
FROM_ABOVE = (0.25, 0.0, 1.0)
#: Shipped presets among the round trip's lights.
ROUND_TRIP_PRESETS = ("studio", "sunset", "forest")
#: Photos taller than this are shrunk to this height first.
MAX_HEIGHT = 1024
#: Photo files read from the folder.

#: ``relight(image (3, H, W) sRGB, mask (H, W), light (K, 3)) -> (3, H, W) sRGB in [0, 1]``
Relighter = Callable[[torch.Tensor, torch.Tensor, torch.Tensor], torch.Tensor]
#: ``estimate(image (3, H, W) sRGB, mask (H, W)) -> (K, 3) light``
Estimator = Callable[[torch.Tensor, torch.Tensor], torch.Tensor]


def check_lights(lmax: int = 2) -> dict[str, torch.Tensor]:
    """The fixed lights of the checks, (K, 3) each: ``left`` and ``right`` (:data:`SIDE_LEFT`,
    :data:`SIDE_RIGHT`), ``above`` (:data:`FROM_ABOVE`), all three ``3·Y(d) + 0.3`` on l = 0,
    and the presets :data:`ROUND_TRIP_PRESETS` (:func:`relightnet.light.preset_light`)."""
    lights = {"left": side_light(SIDE_LEFT, lmax=lmax), "right": side_light(SIDE_RIGHT, lmax=lmax),
              "above": side_light(FROM_ABOVE, lmax=lmax)}
    return lights | {name: preset_light(name, lmax) for name in ROUND_TRIP_PRESETS}


def side_means(image: torch.Tensor, mask: torch.Tensor) -> tuple[float, float, float]:
    """Mean linear luminance of the person's image-left and image-right halves.

    Args:
        image: (3, H, W) sRGB in [0, 1].
        mask: (H, W) person where > 0.5.

    Returns:
        ``(left, right, split)``: the halves' mean Rec. 709 luminance of linear RGB, split at the
        mask's horizontal centroid ``split`` (pixel units, centres at +0.5; a pixel whose centre
        is left of it is on the left). A half without pixels is NaN.
    """
    dims = check_shape(image, [3, "H", "W"], name="image")
    check_shape(mask, [dims["H"], dims["W"]], name="mask")
    person = mask > 0.5
    if not bool(person.any()):
        raise InputError("mask: empty (no person pixel)")
    cols = torch.arange(dims["W"], dtype=torch.float64) + 0.5
    split = float(cols.expand(dims["H"], -1)[person].mean())
    lum = luminance(srgb_to_linear(image.double().clamp(0, 1)).permute(1, 2, 0))
    on_left = (cols < split)[None].expand(dims["H"], -1)
    halves = [lum[person & side] for side in (on_left, ~on_left)]
    left, right = (float(h.mean()) if h.numel() else math.nan for h in halves)
    return left, right, split


def _number(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def side_contrast(under_left: torch.Tensor, under_right: torch.Tensor, mask: torch.Tensor) -> dict:
    """The side contrast of a photo relit under L_left and under L_right (module docstring).

    Args:
        under_left, under_right: (3, H, W) the relit photos, sRGB in [0, 1].
        mask: (H, W) person where > 0.5.

    Returns:
        ``{"split", "ratio_under_left", "ratio_under_right", "side_contrast"}``: the split column
        and the left/right luminance ratios; None where a ratio is undefined (a dark half).
    """
    a_left, a_right, split = side_means(under_left, mask)
    b_left, b_right, _ = side_means(under_right, mask)
    with_left = a_left / a_right if a_right > 0 else math.nan
    with_right = b_left / b_right if b_right > 0 else math.nan
    contrast = with_left / with_right if with_right > 0 else math.nan
    return {"split": split, "ratio_under_left": _number(with_left), "ratio_under_right": _number(with_right),
            "side_contrast": _number(contrast)}


def model_functions(model=None, device: str = "cpu") -> tuple[Relighter, Estimator]:
    """The relighter and light estimator of a model, as the photo commands run them.

    Args:
        model: a :class:`~relightnet.model.RelightNet`, a
            :class:`~relightnet.pipeline.backends.Predictor`, a checkpoint path (``.pt``) or None
            (the shipped model).
        device: torch device for a checkpoint path or None.

    Returns:
        ``(relight, estimate)``: ``relight(image (3, H, W), mask (H, W), light (K, 3)) -> (3, H, W)``
        sRGB, :func:`~relightnet.pipeline.relight_image` with its defaults (``relight-image``);
        ``estimate(image, mask) -> (K, 3)``, ``Predictor.light`` (``estimate-light``).
    """
    if model is None or isinstance(model, (str, os.PathLike)):
        predict = make_predictor("torch", model, device)
    else:
        predict = as_predictor(model)

    def relight(image: torch.Tensor, mask: torch.Tensor, light: torch.Tensor) -> torch.Tensor:
        return relight_image(predict, image, light, mask, maps=False).image.permute(2, 0, 1)

    def estimate(image: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        return predict.light(image, mask).float().cpu()

    return relight, estimate


def load_photo(path, max_height: int = MAX_HEIGHT) -> tuple[torch.Tensor, tuple[int, int]]:
    """A photo through the bounded image reader, shrunk to ``max_height`` if taller (area average).

    Returns:
        ((3, H, W) sRGB in [0, 1], the file's own (W, H)).

    Raises:
        InputError: naming the file (unreadable, or above the pixel limit).
    """
    from ..io import read_image

    image = read_image(path).permute(2, 0, 1)
    h, w = image.shape[1:]
    if h > max_height:
        size = (max_height, max(1, round(w * max_height / h)))
        image = F.interpolate(image[None], size=size, mode="area")[0].clamp(0, 1)
    return image.contiguous(), (int(w), int(h))


def list_photos(folder) -> list[Path]:
    """The photo files (``.png``, ``.jpg``, ``.jpeg``) of a folder, sorted by name.

    Raises:
        InputError: naming the folder when it is missing, not a folder, or holds no photo file.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: {'not a folder' if folder.exists() else 'no such folder'} "
                         "(expected a folder of photos)")
    paths = sorted(p for p in folder.iterdir()
                   if p.suffix.lower() in PHOTO_SUFFIXES and not p.name.startswith(".") and p.is_file())
    if not paths:
        raise InputError(f"{folder}: no photos ({', '.join(PHOTO_SUFFIXES)}) in the folder")
    return paths


def _light_error(est: torch.Tensor, light: torch.Tensor) -> float:
    est = resize_sh(est.double().cpu(), sh_order_from_count(light.shape[-2], "light"))
    return float(scale_invariant_light_error(est, light.double()))


def check_photo(image: torch.Tensor, mask: torch.Tensor, relight: Relighter, estimate: Estimator,
                lights: dict[str, torch.Tensor] | None = None) -> dict:
    """Both checks on one photo.

    Args:
        image: (3, H, W) sRGB in [0, 1].
        mask: (H, W) person where > 0.5.
        relight, estimate: see :func:`model_functions`.
        lights: name → (K, 3) light, with ``left`` and ``right`` (default :func:`check_lights`).

    Returns:
        :func:`side_contrast`'s dict plus ``round_trip`` and ``baseline`` (light name → error)
        and their medians over the lights, ``round_trip_median`` and ``baseline_median``; and
        ``colour`` (white side light name → :func:`~relightnet.pipeline.photo_colour.colour_figures`
        under :data:`~relightnet.pipeline.photo_colour.COLOUR_LIGHTS`) with the worse of the two,
        ``chroma_shift_p99`` and ``fine_chroma_ratio``.
    """
    lights = check_lights() if lights is None else lights
    missing = [n for n in ("left", "right") if n not in lights]
    if missing:
        raise InputError(f"lights: the side contrast needs the lights {' and '.join(missing)}")
    source = estimate(image, mask)
    relit, trip, base = {}, {}, {}
    for name, light in lights.items():
        out = relight(image, mask, light)
        if name in ("left", "right"):
            relit[name] = out
        trip[name] = _light_error(estimate(out, mask), light)
        base[name] = _light_error(source, light)
    lmax = sh_order_from_count(lights["left"].shape[0], "light")
    colour = {name: colour_figures(image, relight(image, mask, light_from_words(words, lmax)), mask)
              for name, words in COLOUR_LIGHTS.items()}
    row = side_contrast(relit["left"], relit["right"], mask)
    return row | {"round_trip": trip, "baseline": base, "round_trip_median": statistics.median(trip.values()),
                  "baseline_median": statistics.median(base.values()), "colour": colour,
                  **{k: max(c[k] for c in colour.values()) for k in ("chroma_shift_p99", "fine_chroma_ratio")}}


def _photo_row(path: Path, max_height: int, person_models, functions, lights) -> dict:
    from ..segment import segment_person

    row = {"photo": path.name, "status": "ok", "note": ""}
    try:
        image, (w, h) = load_photo(path, max_height)
    except InputError as e:
        return row | {"status": "unreadable", "note": str(e)}
    row |= {"size": list(image.shape[:0:-1]), "original_size": [w, h]}
    try:
        mask = segment_person(image, person_models, name=path.name).mask
    except InputError as e:
        return row | {"status": "no person", "note": str(e)}
    row["person"] = float((mask > 0.5).float().mean())
    return row | check_photo(image, mask, *functions(), lights)


def _medians(rows: list[dict], names: list[str]) -> dict:
    ok = [r for r in rows if r["status"] == "ok"]

    def med(values):
        values = [v for v in values if v is not None]
        return statistics.median(values) if values else None

    per_light = {n: {"round_trip": med(r["round_trip"][n] for r in ok), "baseline": med(r["baseline"][n] for r in ok)}
                 for n in names}
    return {"n_photos": len(rows), "n_checked": len(ok),
            **{k: med(r[k] for r in ok) for k in ("ratio_under_left", "ratio_under_right", "side_contrast",
                                                  "chroma_shift_p99", "fine_chroma_ratio")},
            "round_trip": med(r["round_trip"][n] for r in ok for n in names),
            "baseline": med(r["baseline"][n] for r in ok for n in names), "per_light": per_light}


def photo_checks(model=None, folder=".", *, device: str = "cpu", max_height: int = MAX_HEIGHT,
                 lights: dict[str, torch.Tensor] | None = None, person_models=None,
                 relight: Relighter | None = None, estimate: Estimator | None = None) -> dict:
    """Side contrast and round trip (module docstring) of a model on every photo of a folder.

    Args:
        model: a RelightNet, a Predictor, a checkpoint path or None (the shipped model); loaded
            when the first person is found. Unused where ``relight`` and ``estimate`` are given.
        folder: a folder of photos of people (``.png``, ``.jpg``, ``.jpeg``; no masks).
        device: torch device for a checkpoint path or None.
        max_height: photos taller than this are shrunk to it first.
        lights: name → (K, 3) light (default :func:`check_lights`; needs ``left`` and ``right``).
        person_models: loaded :class:`~relightnet.segment.PersonModels` (made here when None).
        relight, estimate: replace the model's (:func:`model_functions`), e.g. to test the checks.

    Returns:
        ``{"folder", "lights", "max_height", "photos": [row per photo], "median": {...}}``. A
        row has ``photo``, ``status`` (``ok``, ``no person``, ``unreadable``) and ``note``; an
        ``ok`` row also ``size`` / ``original_size`` (W, H), ``person`` (the mask's share of the
        photo) and :func:`check_photo`'s fields. ``median``: over the ``ok`` rows (round trip
        and baseline over photos × lights), and per light (over photos).

    Raises:
        InputError: naming the folder when it holds no readable photo, or no person in any.
    """
    from ..segment import PersonModels

    paths = list_photos(folder)
    lights = check_lights() if lights is None else lights
    person_models = PersonModels() if person_models is None else person_models
    made: list = []  # the model's functions, made once when the first person is found

    def functions():
        if relight is not None and estimate is not None:
            return relight, estimate
        if not made:
            made.append(model_functions(model, device))
        return relight or made[0][0], estimate or made[0][1]

    rows = [_photo_row(p, max_height, person_models, functions, lights) for p in paths]
    if all(r["status"] == "unreadable" for r in rows):
        raise InputError(f"{folder}: no readable photos ({len(rows)} file(s); first: {rows[0]['note']})")
    if not any(r["status"] == "ok" for r in rows):
        raise InputError(f"{folder}: no person found in any photo")
    names = list(lights)
    return {"folder": str(folder), "lights": names, "max_height": max_height, "photos": rows,
            "median": _medians(rows, names)}


def _cell(x, digits: int = 2) -> str:
    return "–" if x is None else f"{x:.{digits}f}"


def format_photo_report(result: dict, name: str = "model") -> str:
    """Markdown tables of :func:`photo_checks`'s result: one row per photo and the median row,
    then the round trip per light."""
    lines = [f"Real photos ({name}, {result['folder']}): side contrast = left/right luminance ratio under the "
             "left light ÷ under the right light (target ≥ 4; 1: the light changes nothing); round trip = "
             "scale-invariant error of the light estimated back from the photo relit to each light "
             f"({', '.join(result['lights'])}), median over the lights; baseline = the light estimated from the "
             "original photo against the same lights; chroma shift p99 and fine chroma (relit ÷ photo) under white "
             "side lights, the worse of the two (photo_colour; targets ≤ 0.15 and ≤ 1.15).", "",
             "| photo | size | person | L/R, left light | L/R, right light | side contrast | round trip | baseline "
             "| chroma shift p99 | fine chroma | note |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in result["photos"]:
        if r["status"] != "ok":
            lines.append(f"| {r['photo']} | {'×'.join(map(str, r.get('size', []))) or '–'} | – | – | – | – | – | – "
                         f"| – | – | {r['status']}: {r['note']} |")
            continue
        note = "" if r["size"] == r["original_size"] else "shrunk from " + "×".join(map(str, r["original_size"]))
        lines.append(f"| {r['photo']} | {r['size'][0]}×{r['size'][1]} | {100 * r['person']:.1f}% | "
                     f"{_cell(r['ratio_under_left'])} | {_cell(r['ratio_under_right'])} | "
                     f"{_cell(r['side_contrast'])} | {_cell(r['round_trip_median'], 3)} | "
                     f"{_cell(r['baseline_median'], 3)} | {_cell(r['chroma_shift_p99'], 3)} | "
                     f"{_cell(r['fine_chroma_ratio'])} | {note} |")
    m = result["median"]
    lines += [f"| **median** ({m['n_checked']} of {m['n_photos']} photos; round trip and baseline over photos × "
              f"lights) | | | {_cell(m['ratio_under_left'])} | {_cell(m['ratio_under_right'])} | "
              f"**{_cell(m['side_contrast'])}** | **{_cell(m['round_trip'], 3)}** | **{_cell(m['baseline'], 3)}** | "
              f"**{_cell(m['chroma_shift_p99'], 3)}** | **{_cell(m['fine_chroma_ratio'])}** | |",
              "", "Round trip per light (median over photos):", "",
              "| light | round trip | baseline |", "|---|---|---|"]
    lines += [f"| {n} | {_cell(v['round_trip'], 3)} | {_cell(v['baseline'], 3)} |" for n, v in m["per_light"].items()]
    return "\n".join(lines) + "\n"


def write_photo_report(result: dict, out, name: str = "model") -> tuple[Path, Path]:
    """Write :func:`photo_checks`'s result into the folder ``out`` (made if needed), each file
    atomically: ``photo_checks.md`` (:func:`format_photo_report`) and ``photo_checks.json``.

    Returns:
        The two paths (markdown, JSON).
    """
    import json

    from ..io import atomic_write

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    md, js = out / "photo_checks.md", out / "photo_checks.json"
    with atomic_write(md, "w") as f:
        f.write(f"# Real-photo checks: {name}\n\n{format_photo_report(result, name)}")
    with atomic_write(js, "w") as f:
        json.dump(result | {"model": name}, f, indent=2)
    return md, js
