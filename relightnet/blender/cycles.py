"""Render an exported scene with Cycles on the CPU: linear EXR and 8-bit PNG frames.

Settings (:func:`configure_cycles`): path tracing on the CPU with a fixed number of samples
per pixel (no adaptive sampling, no denoising unless asked, no clamping — an unbiased
reference), diffuse bounces only (``bounces`` = Cycles' ``max_bounces`` and
``diffuse_bounces``: 0 is direct light with shadows, like relightnet's PRT without
interreflection), caustics off, a transparent film (alpha = coverage, background 0 as in
relightnet's renders), the "Standard" view transform (plain sRGB display, no AgX tone map).

Radiometric scale: a relightnet render is ``albedo ⊙ (T·L)`` with T carrying no 1/π
(docs/design.md, "Transport and shading"), i.e. albedo × irradiance; Cycles' diffuse BSDF returns radiance,
albedo × irradiance / π. So for the same world, **relightnet = π × Cycles**, measured by the
sphere test (a white-ish sphere under a constant world of radiance c renders as albedo·c in
Cycles and albedo·π·c in relightnet).
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError
from ._bpy import import_bpy, quiet
from .geometry import check_blend_geometry

logger = logging.getLogger(__name__)

__all__ = ["CYCLES_TO_RELIGHTNET", "CyclesFrame", "configure_cycles", "open_blend", "read_image_pixels",
           "render_current", "render_blend", "check_render_settings", "MAX_SAMPLES", "MAX_FRAMES",
           "MAX_DENOISE_PIXELS"]

#: Most Cycles samples per pixel a .blend may ask for (relightnet's references use 64-1024).
MAX_SAMPLES = 4096
#: Most frames rendered from one .blend (an hour at 30 fps is 108,000).
MAX_FRAMES = 200_000
#: The largest render OpenImageDenoise may denoise within the 2 GB command budget: denoising held
#: ~700 bytes a pixel on top of the render (a 2000² render: 3.6 GB peak denoised, 0.87 GB not).
MAX_DENOISE_PIXELS = 1_500_000

#: relightnet's pixel values are π times Cycles' for the same scene (module docstring).
CYCLES_TO_RELIGHTNET = float(np.pi)

_SAMPLE = re.compile(r"Sample (\d+)/(\d+)")


def configure_cycles(scene, spp: int | None = None, bounces: int | None = None, threads: int | None = None,
                     denoise: bool | None = None, filter_width: float | None = None, seed: int | None = None) -> None:
    """Set a Blender scene up for CPU Cycles; ``None`` leaves a setting as the scene has it.

    Always set: CPU device, no adaptive sampling, no sample clamping, no caustics, glossy /
    transmission / volume bounces 0, transparent film, Standard view transform.

    Args:
        scene: a ``bpy.types.Scene``.
        spp: samples per pixel (≥ 1). bounces: diffuse bounces (≥ 0).
        threads: CPU threads (None or 0: all cores). denoise: OpenImageDenoise.
        filter_width: pixel filter width in pixels (Blender's default 1.5; 0.01 samples the
            pixel centre only, as relightnet's rasterizer does). seed: noise pattern.
    """
    if spp is not None and int(spp) < 1:
        raise InputError(f"spp: expected a positive number of samples, got {spp}")
    if bounces is not None and int(bounces) < 0:
        raise InputError(f"bounces: expected an integer >= 0, got {bounces}")
    if filter_width is not None and not 0.01 <= float(filter_width) <= 10:
        raise InputError(f"filter_width: expected a value in [0.01, 10] pixels, got {filter_width}")
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.caustics_reflective = c.caustics_refractive = False
    c.glossy_bounces = c.transmission_bounces = c.volume_bounces = 0
    if spp is not None:
        c.samples = int(spp)
    if bounces is not None:
        c.max_bounces = c.diffuse_bounces = int(bounces)
    if denoise is not None:
        c.use_denoising = bool(denoise)
    if filter_width is not None:
        c.filter_width = float(filter_width)
    if seed is not None:
        c.seed = int(seed)
    if threads is not None:
        scene.render.threads_mode = "FIXED" if threads else "AUTO"
        if threads:
            scene.render.threads = int(threads)
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    s = scene.render.image_settings
    s.file_format = "OPEN_EXR"
    s.color_mode = "RGBA"
    s.color_depth = "32"
    s.exr_codec = "ZIP"


def read_image_pixels(image) -> np.ndarray:
    """(H, W, C) float32 pixels of a ``bpy.types.Image``, row 0 at the top (Blender stores bottom-up)."""
    w, h = image.size
    c = image.channels
    buf = np.empty(w * h * c, dtype=np.float32)
    image.pixels.foreach_get(buf)
    return np.ascontiguousarray(buf.reshape(h, w, c)[::-1])


def check_render_settings(path, width: int, height: int, percent: int, samples: int, n_frames: int,
                          denoise: bool = False) -> None:
    """Refuse a .blend's render settings above the limits before Blender renders anything:
    the output size (resolution × percentage) above :func:`~relightnet.io.limits.max_pixels`
    (``--max-pixels``), more than :data:`MAX_SAMPLES` samples or :data:`MAX_FRAMES` frames, a
    denoised output (``denoise``) above :data:`MAX_DENOISE_PIXELS`.

    Raises:
        InputError: naming the file and the setting.
    """
    from ..io.limits import check_pixels

    w, h = int(width) * int(percent) // 100, int(height) * int(percent) // 100
    check_pixels(w, h, f"{path}: render output")
    if not 1 <= int(samples) <= MAX_SAMPLES:
        raise InputError(f"{path}: asks for {samples} Cycles samples per pixel; 1 to {MAX_SAMPLES} are rendered "
                         "(--spp overrides the file)")
    if not 1 <= int(n_frames) <= MAX_FRAMES:
        raise InputError(f"{path}: asks for {n_frames} frames; 1 to {MAX_FRAMES} are rendered (--frames)")
    if denoise and w * h > MAX_DENOISE_PIXELS:
        raise InputError(f"{path}: denoising a {w}x{h} render ({w * h / 1e6:.1f} MP) takes about "
                         f"{(0.5e9 + 800 * w * h) / 2**30:.1f} GiB; at most {MAX_DENOISE_PIXELS / 1e6:.1f} MP are "
                         "denoised (--no-denoise, or a smaller render)")


def open_blend(path) -> object:
    """Open a .blend file as Blender's current session; returns its scene."""
    bpy = import_bpy()
    path = Path(path)
    if path.suffix.lower() != ".blend":
        raise InputError(f"{path}: expected a Blender .blend file")
    if not path.is_file():
        raise InputError(f"{path}: no such .blend file")
    bpy.context.preferences.filepaths.use_scripts_auto_execute = False
    check_blend_geometry(path)  # before Blender builds the scene's modifiers
    try:  # the file's scripts never run: no auto-run text blocks or handlers, Python drivers disabled
        with quiet((1, 2)):  # (Blender prints a driver it did not run over several lines: logged at DEBUG)
            bpy.ops.wm.open_mainfile(filepath=str(path.resolve()), load_ui=False, use_scripts=False)
    except RuntimeError as e:
        msg = str(e).strip().splitlines()[-1] if str(e).strip() else "unreadable"
        raise InputError(f"{path}: cannot open with Blender ({msg})") from None
    scene = bpy.context.scene
    if scene.camera is None:
        raise InputError(f"{path}: the scene has no camera")
    return scene


def render_current(exr_path=None, progress=None) -> tuple[np.ndarray, float]:
    """Render the current frame of Blender's current scene to an EXR file.

    Args:
        exr_path: where the RGBA float32 EXR goes (written by Blender once the frame is rendered, then read
            back); None: a temporary folder made after the render and removed.
        progress: optional callable ``(done_samples, total_samples)``, called while rendering.

    Returns:
        (H, W, 4) float32 linear RGBA (row 0 at the top) and the render time in seconds.
    """
    bpy = import_bpy()

    def on_stats(*args):
        m = _SAMPLE.search(str(args[0]) if args else "")
        if m and progress is not None:
            progress(int(m.group(1)), int(m.group(2)))

    handlers = bpy.app.handlers.render_stats
    handlers.append(on_stats)
    try:
        t0 = time.perf_counter()
        with quiet((1,)):
            bpy.ops.render.render()
        seconds = time.perf_counter() - t0
    finally:
        handlers.remove(on_stats)
    with contextlib.ExitStack() as stack:
        if exr_path is None:
            exr_path = Path(stack.enter_context(tempfile.TemporaryDirectory())) / "frame.exr"
        with quiet((1,)):
            bpy.data.images["Render Result"].save_render(filepath=str(exr_path))
        img = bpy.data.images.load(str(exr_path), check_existing=False)
        try:
            px = read_image_pixels(img)
        finally:
            bpy.data.images.remove(img)
    if px.shape[-1] == 3:
        px = np.concatenate([px, np.ones_like(px[..., :1])], axis=-1)
    return px, seconds


@dataclass(frozen=True, eq=False)
class CyclesFrame:
    """One rendered frame: relightnet frame index (Blender frame = index + frame_start),
    (H, W, 4) linear RGBA, render seconds, and the files written (or None)."""

    index: int
    rgba: torch.Tensor
    seconds: float
    exr: Path | None = None
    png: Path | None = None


def _frame_range(scene, frames) -> range:
    start, end = scene.frame_start, scene.frame_end
    n = end - start + 1
    if frames is None:
        return range(n)
    a, b = frames
    a = 0 if a is None else int(a)
    b = n if b is None else int(b)
    if not 0 <= a < b <= n:
        raise InputError(f"frames: expected START:END within 0:{n} (the scene has {n} frames), got {a}:{b}")
    return range(a, b)


def _render_frame(out: Path | None, t: int, tick) -> tuple[np.ndarray, float, Path | None]:
    """Render frame ``t``; with ``out``, Blender saves it under a temporary name beside ``frame_NNNNN.exr``
    (:func:`~relightnet.io.atomic.temp_path`: the next render into ``out`` removes it if this one is killed
    while saving) that exists only once the frame is rendered, renamed when read back. So a render killed
    mid-frame leaves nothing in ``out`` (and nothing in TMPDIR: :func:`~relightnet.blender._bpy.import_bpy`)."""
    if out is None:
        return (*render_current(None, tick), None)
    from ..io.atomic import remove_stale, temp_path

    exr = out / f"frame_{t:05d}.exr"
    remove_stale(exr)
    raw = temp_path(exr, "render")
    try:
        px, seconds = render_current(raw, tick)
        os.replace(raw, exr)
    finally:
        raw.unlink(missing_ok=True)
    return px, seconds, exr


def render_blend(
    path,
    out_dir=None,
    spp: int | None = None,
    bounces: int | None = None,
    frames: tuple[int | None, int | None] | None = None,
    threads: int | None = None,
    denoise: bool | None = None,
    filter_width: float | None = None,
    seed: int | None = None,
    exposure="auto",
    progress: bool = False,
) -> Iterator[CyclesFrame]:
    """Render a .blend (from :func:`relightnet.blender.export_scene`) frame by frame with Cycles.

    Args:
        path: the .blend file.
        out_dir: folder for ``frame_NNNNN.exr`` (linear RGBA float32, Blender's writer) and
            ``frame_NNNNN.png`` (8-bit sRGB, black background, ``exposure`` applied); None
            writes nothing (frames are only yielded).
        spp, bounces, threads, denoise, filter_width, seed: :func:`configure_cycles`
            (None keeps the file's settings).
        frames: (start, end) relightnet frame indices, end exclusive (None: all frames).
        exposure: ``"auto"`` (chosen on the first frame's covered pixels, then fixed) or a
            linear multiplier for the PNGs.
        progress: show a progress bar of samples on stderr.

    Yields:
        :class:`CyclesFrame` per frame.
    """
    from ..io import write_image
    from ..light.visualize import auto_exposure

    out = None if out_dir is None else Path(out_dir)
    if out is not None and out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a folder")
    scene = open_blend(path)
    configure_cycles(scene, spp, bounces, threads, denoise, filter_width, seed)
    todo = _frame_range(scene, frames)
    r = scene.render
    check_render_settings(path, r.resolution_x, r.resolution_y, r.resolution_percentage, scene.cycles.samples,
                          len(todo), bool(scene.cycles.use_denoising))
    if out is not None:
        from ..io.atomic import remove_stale

        out.mkdir(parents=True, exist_ok=True)
        remove_stale(out / "frames")  # the staging folder of a killed render of an older version
    total = len(todo) * scene.cycles.samples
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=total, desc="cycles", unit="spp", leave=True)
    scale = None if exposure == "auto" else float(exposure)
    try:
        for k, t in enumerate(todo):
            with quiet((1, 2)):  # the frame's drivers are evaluated (a Python one is refused, in several lines)
                scene.frame_set(scene.frame_start + t)

            def tick(done, n, base=k * scene.cycles.samples):
                if bar is not None:
                    bar.n = base + min(done, n)
                    bar.refresh()

            px, seconds, exr = _render_frame(out, t, tick)
            rgba = torch.from_numpy(px)
            png = None
            if out is not None:
                png = exr.with_suffix(".png")
                if scale is None:
                    scale = auto_exposure(rgba[..., :3], rgba[..., 3] > 0.5)
                write_image(png, rgba[..., :3] * scale)
            logger.debug("frame %d: %.2f s", t, seconds)
            yield CyclesFrame(t, rgba, seconds, exr, png)
    finally:
        if bar is not None:
            bar.close()
