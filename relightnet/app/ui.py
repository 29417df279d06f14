"""The Gradio page of ``relightnet app``: relight a photo by hand, or a video.

Photo tab: open a photo (or make the example person) → the CNN runs once
(:class:`~relightnet.app.session.RelightSession`) and the person's mask is shown; choose a light
by direction (drag it on the sphere pad, click the lit sphere, or move the sliders: azimuth,
elevation, size, power, colour, ambient), a preset, an HDRI file or a background plate; the
relit photo is redrawn beside the original on every change (re-shading only) with the
diffuse-sphere preview and the light in words; download the relit PNG and the light (.npz).
Video tab: ``relight-video`` with a progress bar.

Everything the app writes goes under its own temporary folder (``workdir``), which Gradio also
uses for its uploads and cache; nothing else is written. Errors (a photo over the pixel
limit, no person, a bad light) are shown as the CLI's one-line messages.
"""


import itertools
import logging
from pathlib import Path

import numpy as np

__all__ = ["build_app", "SPHERE_SIZE"]

logger = logging.getLogger("relightnet.app")

#: Side of the clickable light sphere, pixels.
SPHERE_SIZE = 192

#: The drag pad: a disc (the front of the sphere) with a dot at the light's direction. Dragging
#: on it sets ``props.value`` to "x,y" (the pointer in [0, 1]² of the pad) and fires ``input``
#: at most every 50 ms while the pointer moves, and once more when it is released.
_PAD_HTML = (
    f"<div class='light-pad' style='width:{SPHERE_SIZE}px;height:{SPHERE_SIZE}px;border-radius:50%;"
    "position:relative;touch-action:none;cursor:crosshair;"
    "background:radial-gradient(circle at 35% 30%, #fff, #999 60%, #333)'>"
    "<div style='position:absolute;width:12px;height:12px;border-radius:50%;background:#f53;"
    "left:calc(${(value || \"0.5,0.5\").split(\",\")[0] * 100}% - 6px);"
    "top:calc(${(value || \"0.5,0.5\").split(\",\")[1] * 100}% - 6px)'></div></div>"
)
_PAD_JS = """
let last = 0, down = false;
function send(ev, force) {
  const pad = element.querySelector('.light-pad');
  if (!pad) return;
  const r = pad.getBoundingClientRect();
  const x = Math.min(Math.max((ev.clientX - r.left) / r.width, 0), 1);
  const y = Math.min(Math.max((ev.clientY - r.top) / r.height, 0), 1);
  props.value = x.toFixed(4) + ',' + y.toFixed(4);
  const now = Date.now();
  if (force || now - last > 50) { last = now; trigger('input'); }
}
element.addEventListener('pointerdown', (ev) => { down = true; send(ev, true); });
element.addEventListener('pointermove', (ev) => { if (down) send(ev, false); });
window.addEventListener('pointerup', (ev) => { if (down) { down = false; send(ev, true); } });
"""


def _to_u8(img) -> np.ndarray:
    return (img.clamp(0, 1).numpy() * 255).round().astype(np.uint8)


class _Handlers:
    """The page's callbacks (plain methods; Gradio calls them with the components' values)."""

    def __init__(self, workdir: Path, predictor):
        self.workdir, self.predict, self.counter = Path(workdir), predictor, itertools.count()

    def _predictor(self):
        if self.predict is None:
            from ..pipeline.backends import make_predictor

            self.predict = make_predictor()
        return self.predict

    def _new_path(self, stem: str, suffix: str) -> Path:
        d = self.workdir / "out" / f"{next(self.counter):05d}"
        d.mkdir(parents=True, exist_ok=True)
        return d / f"{stem}{suffix}"

    @staticmethod
    def _fail(e: Exception):
        import gradio as gr

        raise gr.Error(str(e), print_exception=False)

    def open_photo(self, path):
        from ..errors import RelightError
        from .session import RelightSession, load_photo

        if not path:
            return None, None, None
        try:
            relighter = RelightSession(self._predictor(), load_photo(path))
        except (RelightError, ValueError, OSError) as e:
            self._fail(e)
        return relighter, _to_u8(relighter.photo.image.permute(1, 2, 0)), _to_u8(relighter.mask_overlay())

    def example_photo(self):
        from .examples import example_person

        return str(example_person(self.workdir / "examples"))

    def relight(self, relighter, source, az, el, size, power, color, ambient, preset, hdri, plate, fov):
        from ..errors import RelightError
        from .controls import light_of, sphere_preview, words_of

        words = words_of(az, el, size, power, color, ambient)
        try:
            light = light_of(source, words, preset, hdri, plate, fov)
        except (RelightError, ValueError, OSError) as e:
            self._fail(e)
        marker = (az, el) if source == "direction" else (None, None)
        sphere = sphere_preview(light, SPHERE_SIZE, *marker)
        if relighter is None:
            return None, sphere, words, light
        return relighter.relight_u8(light).numpy(), sphere, words, light

    def download(self, relighter, light, source):
        from ..errors import RelightError
        from ..io import write_image
        from ..sh import save_light

        if relighter is None or light is None:
            self._fail(RelightError("open a photo first"))
        png = self._new_path("relit", ".png")
        write_image(png, relighter.relight(light), srgb=False, alpha=relighter.photo.alpha)
        npz = save_light(self._new_path(f"light_{source.replace(' ', '_')}", ".npz"), light)
        return [str(png), str(npz)]

    def run_video(self, video, words, preset, progress=None):
        from ..errors import RelightError
        from ..light import load_light
        from ..pipeline.relight_video import relight_video

        if not video:
            self._fail(RelightError("video: upload a video"))
        try:
            light = load_light(preset or words)
            out = self._new_path("relit", ".mp4")
            relight_video(self._predictor(), video, None, light, out, progress=True)
        except (RelightError, ValueError, OSError) as e:
            self._fail(e)
        return str(out)


def _pointed(index):
    """The sliders' (azimuth, elevation, source) for a click on the sphere at pixel ``index`` = (x, y).

    ``index`` is None when the browser clicked an image it had not loaded yet (it has no pixel size
    then): the sliders are left as they are (``gradio.skip()`` each), instead of an error.
    """
    import gradio as gr

    from .controls import sphere_point_to_direction

    if index is None:
        return gr.skip(), gr.skip(), gr.skip()
    az, el = sphere_point_to_direction(index[0] + 0.5, index[1] + 0.5, SPHERE_SIZE)
    return round(az), round(el), "direction"


def _photo_tab(gr) -> dict:
    """The photo tab's components, by name."""
    from ..names import light_presets
    from .controls import LIGHT_SOURCES

    c = {}
    with gr.Row():
        with gr.Column(scale=1):
            c["upload"] = gr.File(label="Photo (PNG/JPEG)", file_types=["image"], type="filepath",
                                  elem_id="photo-upload")
            c["example"] = gr.Button("Example person", elem_id="example-button")
            c["source"] = gr.Radio(list(LIGHT_SOURCES), value="direction", label="Light", elem_id="light-source")
            c["pad"] = gr.HTML("0.5,0.5", html_template=_PAD_HTML, js_on_load=_PAD_JS,
                               label="Drag the light's direction", elem_id="light-pad")
            c["sphere"] = gr.Image(label="The light on a white sphere (click it to point the light)",
                                   interactive=False, height=SPHERE_SIZE, width=SPHERE_SIZE, elem_id="light-sphere",
                                   format="png")
            c["az"] = gr.Slider(-180, 180, value=-40, step=1, label="Azimuth (° from the camera; − = left)",
                                elem_id="az")
            c["el"] = gr.Slider(-90, 90, value=30, step=1, label="Elevation (°; + = from above)", elem_id="el")
            c["size"] = gr.Slider(0, 180, value=20, step=1, label="Size (° across)", elem_id="size")
            c["power"] = gr.Slider(0, 10, value=3, step=0.1, label="Strength", elem_id="power")
            c["color"] = gr.ColorPicker(value="#ffffff", label="Colour", elem_id="color")
            c["ambient"] = gr.Slider(0, 2, value=0.2, step=0.05, label="Ambient", elem_id="ambient")
            c["preset"] = gr.Dropdown(light_presets(), value="studio", label="Preset", elem_id="preset")
            c["hdri"] = gr.File(label="HDRI (.exr/.hdr)", file_types=[".exr", ".hdr"], type="filepath")
            c["plate"] = gr.File(label="Background plate (its light)", file_types=["image"], type="filepath")
            c["fov"] = gr.Slider(10, 120, value=60, step=1, label="Plate field of view (°)")
        with gr.Column(scale=2):
            c["words"] = gr.Textbox(label="The light in words (the CLI's --light takes it)", interactive=False,
                                    elem_id="light-words")
            with gr.Row():
                c["original"] = gr.Image(label="Original", interactive=False, format="png", elem_id="original")
                c["relit"] = gr.Image(label="Relit", interactive=False, format="png", elem_id="relit")
            c["mask"] = gr.Image(label="The person's mask", interactive=False, format="png", elem_id="mask")
            c["save"] = gr.Button("Download the relit photo and the light", elem_id="download-button")
            c["files"] = gr.File(label="Downloads", file_count="multiple", interactive=False, elem_id="downloads")
    return c


def build_app(workdir, predictor=None):
    """The app as a ``gradio.Blocks`` (not launched).

    Args:
        workdir: the app's temporary folder (must exist): every file it writes goes here.
        predictor: the CNN (default: the shipped model, made at the first photo).

    Returns:
        ``gradio.Blocks``.
    """
    import gradio as gr

    from ..names import light_presets

    h = _Handlers(workdir, predictor)

    def click_sphere(evt: gr.SelectData):
        return _pointed(evt.index)

    def drag_pad(value):
        from .controls import sphere_point_to_direction

        x, y = (float(v) for v in str(value).split(","))
        az, el = sphere_point_to_direction(x * SPHERE_SIZE, y * SPHERE_SIZE, SPHERE_SIZE)
        return round(az), round(el), "direction"

    def run_video(video, words, preset, progress=gr.Progress(track_tqdm=True)):
        return h.run_video(video, words, preset, progress)

    with gr.Blocks(title="relightnet") as app:
        gr.Markdown("## relightnet — relight a person with any light")
        relighter, light = gr.State(None), gr.State(None)
        with gr.Tab("Photo"):
            c = _photo_tab(gr)
        with gr.Tab("Video"):
            video = gr.Video(label="Video", sources=["upload"])
            vwords = gr.Textbox(value="key:az=-40,el=30,size=20,power=3 + ambient:0.2", label="Light in words")
            vpreset = gr.Dropdown([""] + light_presets(), value="", label="or a preset")
            go = gr.Button("Relight the video")
            vout = gr.Video(label="Relit video")
        controls = [relighter] + [c[k] for k in ("source", "az", "el", "size", "power", "color", "ambient", "preset",
                                               "hdri", "plate", "fov")]
        shown = [c["relit"], c["sphere"], c["words"], light]
        opts = {"trigger_mode": "always_last", "show_progress": "hidden"}
        c["upload"].change(h.open_photo, c["upload"], [relighter, c["original"], c["mask"]]).then(
            h.relight, controls, shown)
        c["example"].click(h.example_photo, None, c["upload"])
        for k in ("az", "el", "size", "power", "ambient", "source", "color", "preset", "hdri", "plate", "fov"):
            c[k].change(h.relight, controls, shown, **opts)
        c["sphere"].select(click_sphere, None, [c["az"], c["el"], c["source"]])
        c["pad"].input(drag_pad, c["pad"], [c["az"], c["el"], c["source"]], trigger_mode="always_last",
                       show_progress="hidden")
        c["save"].click(h.download, [relighter, light, c["source"]], c["files"])
        go.click(run_video, [video, vwords, vpreset], vout)
        app.load(h.relight, controls, shown)
    return app
