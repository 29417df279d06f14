"""Hostile .blend files made with bpy at test time (nothing committed), and the capped runs that read them.

A .blend of 83 KB asked for 20000² pixels × 16.7 M samples × 10⁶ frames; ``blender-render``
ran past 120 s without applying ``--max-pixels`` and left a folder in OUT and files in /tmp. Each
case here writes a real .blend through Blender's own Python module (a camera, a cube, the render
settings, optionally a text block registered to run on load and a Python driver, both writing a
marker file if they ever run) and returns the ``relightnet`` command that reads it; the run goes
through ``tests/fuzz/resource_runner.run_capped`` (address-space and wall-clock caps, own TMPDIR).

    python tests/blender/hostile_blends.py NAME FOLDER   # one case, its result as JSON (SECURITY.md's table)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "fuzz"))
from resource_runner import Case, run_capped  # noqa: E402

sys.path.pop(0)

#: Files a case's scripts would write if they ran (relative to the case folder).
MARKERS = ("text-block-ran", "driver-ran")


def write_blend(path: Path, side: int = 64, percent: int = 100, samples: int = 4, frames: int = 1,
                scripts: bool = False, modifier: dict | None = None) -> Path:
    """A .blend of a camera looking at a lit cube: ``side``² pixels at ``percent`` %, ``samples`` Cycles samples,
    ``frames`` frames; with ``scripts``, a text block registered to run on load and a Python driver on the
    camera, each writing its marker file (:data:`MARKERS`) beside the .blend if it runs; ``modifier``: one
    modifier on the cube, ``{"type": TYPE, attribute: value, ...}``."""
    from relightnet.blender._bpy import quiet, reset

    bpy = reset()
    scene = bpy.context.scene
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    cam.location = (0.0, -6.0, 0.0)
    cam.rotation_euler = (1.5708, 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    cube = bpy.data.objects.new("cube", bpy.data.meshes.new("cube"))
    cube.data.from_pydata([(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], [],
                          [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)])
    scene.collection.objects.link(cube)
    if modifier is not None:
        m = cube.modifiers.new("m", modifier["type"])
        for k, v in modifier.items():
            if k != "type":
                setattr(m, k, v)
    world = bpy.data.worlds.new("world")
    world.color = (0.8, 0.8, 0.8)
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.render.resolution_x = scene.render.resolution_y = side
    scene.render.resolution_percentage = percent
    scene.cycles.samples = samples
    scene.frame_start, scene.frame_end = 0, frames - 1
    if scripts:
        folder = path.resolve().parent
        text = bpy.data.texts.new("autorun.py")
        text.write(f"open({str(folder / MARKERS[0])!r}, 'w').write('ran')\n")
        text.use_module = True  # "Register": Blender runs it when the file is loaded with scripts trusted
        drv = cam.driver_add("location", 0).driver
        drv.type = "SCRIPTED"
        drv.expression = f"__import__('builtins').open({str(folder / MARKERS[1])!r}, 'w').write('ran') or 0"
    with quiet((1, 2)):  # the driver is evaluated (and refused) while saving
        bpy.ops.wm.save_as_mainfile(filepath=str(path.resolve()), copy=True)
    return path


def _render(blend: str, *extra: str, expect: str = "error") -> Case:
    outputs = ("out/frame_00000.exr", "out/frame_00000.png") if expect == "ok" else ()
    return Case(["-q", "blender-render", blend, "--threads", "1", *extra, "--out", "out"], blend, expect=expect,
                outputs=outputs)


def huge_settings(folder: Path) -> Case:
    """20000² pixels × 16,777,216 samples × 10⁶ frames: refused for its size, in one line."""
    write_blend(folder / "huge.blend", side=20000, samples=16_777_216, frames=1_000_000, scripts=True)
    return _render("huge.blend")


def huge_samples(folder: Path) -> Case:
    """The same at 1 % (200² pixels, within the limit): refused for its 16.7 M samples."""
    write_blend(folder / "spp.blend", side=20000, percent=1, samples=16_777_216, frames=1_000_000)
    return _render("spp.blend")


def huge_frames(folder: Path) -> Case:
    """The same with ``--spp 4``: refused for its 10⁶ frames."""
    write_blend(folder / "frames.blend", side=20000, percent=1, samples=16_777_216, frames=1_000_000)
    return _render("frames.blend", "--spp", "4")


def capped_by_options(folder: Path) -> Case:
    """The same with ``--spp 4 --frames 0:1``: one 200² frame rendered, its scripts never run."""
    write_blend(folder / "capped.blend", side=20000, percent=1, samples=16_777_216, frames=1_000_000, scripts=True)
    return _render("capped.blend", "--spp", "4", "--frames", "0:1", expect="ok")


def max_pixels_option(folder: Path) -> Case:
    """A 64² .blend under ``--max-pixels 1000``: the option applies to the file's own render size."""
    write_blend(folder / "small.blend")
    return _render("small.blend", "--max-pixels", "1000")


def autorun_scripts(folder: Path) -> Case:
    """A valid 64² .blend with an auto-run text block and a Python driver: rendered, neither runs."""
    write_blend(folder / "scripts.blend", scripts=True)
    return _render("scripts.blend", expect="ok")


def subdivided_cube(folder: Path) -> Case:
    """A cube under a subdivision surface of render level 11, Blender's most (6 · 4¹¹ = 25 M faces): refused
    before it is built."""
    write_blend(folder / "subsurf.blend", modifier={"type": "SUBSURF", "levels": 1, "render_levels": 11})
    return _render("subsurf.blend")


def arrayed_cube(folder: Path) -> Case:
    """A cube arrayed 5 million times (30 M faces; Blender alone, opening it, took 2.8 GB before the check
    came before the opening): refused before it is built."""
    write_blend(folder / "array.blend", modifier={"type": "ARRAY", "count": 5_000_000})
    return _render("array.blend")


def geometry_nodes(folder: Path) -> Case:
    """A geometry-nodes modifier (its output unknown until evaluated): refused."""
    write_blend(folder / "nodes.blend", modifier={"type": "NODES"})
    return _render("nodes.blend")


def slow_render(folder: Path) -> Case:
    """2000² pixels (4 MP) × 4096 samples on one thread, not denoised: hours, so the wall cap kills it mid-frame."""
    write_blend(folder / "slow.blend", side=2000, samples=4096)
    return _render("slow.blend", "--no-denoise", expect="killed")


def denoised_4mp(folder: Path) -> Case:
    """2000² pixels denoised (Blender's default for a new file): OpenImageDenoise would hold ~3.6 GB; refused."""
    write_blend(folder / "denoised.blend", side=2000, samples=16)
    return _render("denoised.blend")


CASES = {
    "blend-20000x20000-16.7M-spp-1e6-frames": huge_settings,
    "blend-16.7M-spp-at-1-percent": huge_samples,
    "blend-1e6-frames-with-spp-4": huge_frames,
    "blend-capped-by-spp-and-frames": capped_by_options,
    "blend-64x64-under-max-pixels-1000": max_pixels_option,
    "blend-autorun-text-and-driver": autorun_scripts,
    "blend-4MP-4096-spp-killed": slow_render,
    "blend-subdivision-level-11": subdivided_cube,
    "blend-array-of-5e6": arrayed_cube,
    "blend-geometry-nodes": geometry_nodes,
    "blend-4MP-denoised": denoised_4mp,
}
#: Wall-clock cap of the killed case (seconds): long enough for Blender to start rendering.
KILL_AFTER = 20.0

if __name__ == "__main__":
    name, where = sys.argv[1], Path(sys.argv[2])
    where.mkdir(parents=True, exist_ok=True)
    case = CASES[name](where)
    res = run_capped(case, where, wall=KILL_AFTER if case.expect == "killed" else 120.0)
    print(json.dumps({"rc": res.rc, "rss_mb": res.rss >> 20, "wall": round(res.wall, 2), "left": res.leftovers,
                      "timed_out": res.timed_out, "stderr": res.stderr[-600:]}))
