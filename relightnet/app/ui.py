"""The Gradio page of ``relightnet app``: relight a photo by hand, or a video.

Photo tab: open a photo (or make the example person) → the CNN runs once
(:class:`~relightnet.app.session.RelightSession`) and the person's mask is shown; choose a light
by direction (click the sphere or move the sliders: azimuth, elevation, size, power, colour,
ambient), a preset, an HDRI file or a background plate; the relit photo is redrawn beside the
original on every change (re-shading only) with the diffuse-sphere preview and the light in
words; download the relit PNG and the light (.npz). Video tab: ``relight-video`` with a
progress bar.

Everything the app writes goes under its own temporary folder (``workdir``), which Gradio also
uses for its uploads and cache; nothing else is written. Errors (a photo over the pixel
limit, no person, a bad light) are shown as the CLI's one-line messages.
"""

from __future__ import annotations

import itertools
import logging
from pathlib import Path

import numpy as np

__all__ = ["build_app", "SPHERE_SIZE"]

logger = logging.getLogger("relightnet.app")

#: Side of the clickable light sphere, pixels.
SPHERE_SIZE = 192


def _to_u8(img) -> np.ndarray:
    return (img.clamp(0, 1).numpy() * 255).round().astype(np.uint8)


def build_app(workdir, predictor=None):
    """The app as a ``gradio.Blocks`` (not launched).

    Args:
        workdir: the app's temporary folder (must exist): every file it writes goes here.
        predictor: the CNN (default: the shipped model, made at the first photo).

    Returns:
        ``gradio.Blocks``.
    """
    import gradio as gr
    import torch

    from ..errors import RelightError
    from ..names import light_presets
    from .controls import LIGHT_SOURCES, light_of, sphere_point_to_direction, sphere_preview, words_of
    from .session import RelightSession, load_photo

    workdir = Path(workdir)
    counter = itertools.count()
    model = {"predict": predictor}

    def _predictor():
        if model["predict"] is None:
            from ..pipeline.backends import make_predictor

            model["predict"] = make_predictor()
        return model["predict"]

    def _new_path(stem: str, suffix: str) -> Path:
        d = workdir / "out" / f"{next(counter):05d}"
        d.mkdir(parents=True, exist_ok=True)
        return d / f"{stem}{suffix}"

    def _fail(e: Exception):
        raise gr.Error(str(e), print_exception=False)

    def open_photo(path):
        if not path:
            return None, None, None
        try:
            session = RelightSession(_predictor(), load_photo(path))
        except (RelightError, ValueError, OSError) as e:
            _fail(e)
        return session, _to_u8(session.photo.image.permute(1, 2, 0)), _to_u8(session.mask_overlay())

    def example_photo():
        from .examples import example_person

        return str(example_person(workdir / "examples"))

    def relight(session, source, az, el, size, power, color, ambient, preset, hdri, plate, fov):
        words = words_of(az, el, size, power, color, ambient)
        try:
            light = light_of(source, words, preset, hdri, plate, fov)
        except (RelightError, ValueError, OSError) as e:
            _fail(e)
        sphere = sphere_preview(light, SPHERE_SIZE, az, el) if source == "direction" else \
            sphere_preview(light, SPHERE_SIZE)
        if session is None:
            return None, sphere, words, light
        with torch.no_grad():
            out = session.relight(light)
        return _to_u8(out), sphere, words, light

    def click_sphere(evt: gr.SelectData):
        az, el = sphere_point_to_direction(evt.index[0] + 0.5, evt.index[1] + 0.5, SPHERE_SIZE)
        return round(az), round(el), "direction"

    def download(session, light, source):
        from ..io import write_image
        from ..sh import save_light

        if session is None or light is None:
            _fail(RelightError("open a photo first"))
        png = _new_path("relit", ".png")
        write_image(png, session.relight(light), srgb=False, alpha=session.photo.alpha)
        npz = save_light(_new_path(f"light_{source.replace(' ', '_')}", ".npz"), light)
        return [str(png), str(npz)]

    def run_video(video, words, preset, progress=gr.Progress(track_tqdm=True)):
        from ..pipeline.relight_video import relight_video
        from ..sh import load_light

        if not video:
            _fail(RelightError("video: upload a video"))
        try:
            light = load_light(preset or words)
            out = _new_path("relit", ".mp4")
            relight_video(_predictor(), video, None, light, out, progress=True)
        except (RelightError, ValueError, OSError) as e:
            _fail(e)
        return str(out)

    with gr.Blocks(title="relightnet") as app:
        gr.Markdown("## relightnet — relight a person with any light")
        session = gr.State(None)
        light = gr.State(None)
        with gr.Tab("Photo"):
            with gr.Row():
                with gr.Column(scale=1):
                    upload = gr.File(label="Photo (PNG/JPEG)", file_types=["image"], type="filepath",
                                     elem_id="photo-upload")
                    example = gr.Button("Example person", elem_id="example-button")
                    source = gr.Radio(list(LIGHT_SOURCES), value="direction", label="Light",
                                      elem_id="light-source")
                    sphere = gr.Image(label="Light direction: click the sphere", interactive=False,
                                      height=SPHERE_SIZE, width=SPHERE_SIZE, elem_id="light-sphere", format="png")
                    az = gr.Slider(-180, 180, value=-40, step=1, label="Azimuth (° from the camera; − = left)",
                                   elem_id="az")
                    el = gr.Slider(-90, 90, value=30, step=1, label="Elevation (°; + = from above)", elem_id="el")
                    size = gr.Slider(0, 180, value=20, step=1, label="Size (° across)", elem_id="size")
                    power = gr.Slider(0, 10, value=3, step=0.1, label="Strength", elem_id="power")
                    color = gr.ColorPicker(value="#ffffff", label="Colour", elem_id="color")
                    ambient = gr.Slider(0, 2, value=0.2, step=0.05, label="Ambient", elem_id="ambient")
                    preset = gr.Dropdown(light_presets(), value="studio", label="Preset", elem_id="preset")
                    hdri = gr.File(label="HDRI (.exr/.hdr)", file_types=[".exr", ".hdr"], type="filepath")
                    plate = gr.File(label="Background plate (its light)", file_types=["image"], type="filepath")
                    fov = gr.Slider(10, 120, value=60, step=1, label="Plate field of view (°)")
                with gr.Column(scale=2):
                    words = gr.Textbox(label="The light in words (the CLI's --light takes it)", interactive=False,
                                       elem_id="light-words")
                    with gr.Row():
                        original = gr.Image(label="Original", interactive=False, format="png", elem_id="original")
                        relit = gr.Image(label="Relit", interactive=False, format="png", elem_id="relit")
                    mask = gr.Image(label="The person's mask", interactive=False, format="png", elem_id="mask")
                    save = gr.Button("Download the relit photo and the light", elem_id="download-button")
                    files = gr.File(label="Downloads", file_count="multiple", interactive=False, elem_id="downloads")
        with gr.Tab("Video"):
            video = gr.Video(label="Video", sources=["upload"])
            vwords = gr.Textbox(value="key:az=-40,el=30,size=20,power=3 + ambient:0.2", label="Light in words")
            vpreset = gr.Dropdown([""] + light_presets(), value="", label="or a preset")
            go = gr.Button("Relight the video")
            vout = gr.Video(label="Relit video")

        controls = [session, source, az, el, size, power, color, ambient, preset, hdri, plate, fov]
        shown = [relit, sphere, words, light]
        opts = {"trigger_mode": "always_last", "show_progress": "hidden"}
        upload.change(open_photo, upload, [session, original, mask]).then(relight, controls, shown)
        example.click(example_photo, None, upload)
        for c in (az, el, size, power, ambient):
            c.change(relight, controls, shown, **opts)
        for c in (source, color, preset, hdri, plate, fov):
            c.change(relight, controls, shown, **opts)
        sphere.select(click_sphere, None, [az, el, source])
        save.click(download, [session, light, source], files)
        go.click(run_video, [video, vwords, vpreset], vout)
        app.load(relight, controls, shown)
    return app
