"""``relightnet demo``: the whole job on embedded defaults only (shipped CNN, Anny, shipped env maps).

1. ``target.mp4``: a target clip made by the data generator — a person walking under a
   turning light from a held-out env map (``night``) over a background — with its masks
   (``target_masks.mp4``), its clean plate (``plate.mp4``) and its true lights;
2. ``avatar.mp4`` (job 3, :func:`~relightnet.pipeline.avatar`): the Anny avatar walking,
   lit by the light the CNN estimates from the person in the target, smoothed over time,
   composited over the plate; ``side_by_side.mp4`` shows target | avatar;
   ``lights.png`` compares raw, smoothed and true light curves;
3. ``compare/`` (job 4, :func:`~relightnet.pipeline.compare`): 2D vs 3D path against the
   ground truth on generated test sequences (``sequences/``): report.md, plots, side-by-side video;
4. ``lights/<preset>.png``: previews of the preset lights;
5. ``replace/``: the dressed avatar (``--outfit casual``) in place of a person walking across a
   generated scene (``avatar --replace-person``), with the clean plate's PSNR against the true
   background in ``summary.json``;
6. ``motion/``: motion transfer (:mod:`.motion_demo`): a generated source person walks
   (``source.mp4``), the avatar performs the fitted walk in the target (``avatar.mp4``;
   ``avatar --motion-from``), ``side_by_side.mp4`` shows source | avatar; the fit's PA-MPJPE
   against the source's truth in ``summary.json``;
7. ``capture/``: capture (:mod:`.capture_demo`): a generated person turning under one light
   (``source/source.mp4``) is captured (``person.avatar.npz``) and walks in the target under the light
   estimated there (``avatar.mp4``; ``avatar --avatar``), beside the truth (the same person under the
   target's true light, ``truth.mp4``): ``side_by_side.mp4`` shows source | captured | truth; the seen
   share, the texture's error and the PSNR against the truth in ``summary.json``.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import torch

logger = logging.getLogger(__name__)

__all__ = ["run_demo", "DEMO_CLIP"]

#: The generated test clip used as the target: a walk under a turning ``night`` light.
DEMO_CLIP = 7


def _write_target(out: Path, sample) -> dict:
    from ..io import VideoWriter
    from ..io.image import to_uint8
    from ..sh import save_light

    a = sample.arrays
    paths = {"target": out / "target.mp4", "masks": out / "target_masks.mp4", "plate": out / "plate.mp4"}
    with VideoWriter(paths["target"], fps=sample.meta["fps"]) as v:
        for f in a["image_composite"]:
            v.write(f)
    with VideoWriter(paths["masks"], fps=sample.meta["fps"]) as v:
        for m in a["mask"]:
            v.write(np.repeat((m[..., None] > 0.5).astype(np.uint8) * 255, 3, -1))
    plate = to_uint8(torch.from_numpy(a["background"][0])).numpy()
    with VideoWriter(paths["plate"], fps=sample.meta["fps"]) as v:
        for _ in range(a["image_composite"].shape[0]):
            v.write(plate)
    paths["true_lights"] = save_light(out / "target_lights_true.npz", torch.from_numpy(a["light"]))
    return paths


def run_demo(out_dir="out/demo", size: int = 256, frames: int = 48, n_dirs: int = 64, compare_clips: int = 2,
             compare_size: int = 128, compare_frames: int = 24, progress: bool = True) -> dict:
    """Write the demo into ``out_dir``; returns the paths written by name.

    Args:
        size: side of the target clip (square, a multiple of 16).
        frames: frames of the target clip and the avatar video.
        n_dirs: PRT directions of the avatar.
        compare_clips, compare_size, compare_frames: the generated sequences of the comparison.
    """
    from ..body import AnnyBody
    from ..data import SynthConfig, generate_sequence
    from ..io import atomic_write, write_side_by_side
    from ..light import render_presets
    from ..model import load_model
    from ..prt import PrtSettings
    from ..temporal import light_error
    from ..temporal.plot import light_curves_png
    from .avatar import avatar
    from .backends import TorchPredictor
    from .capture_demo import capture_demo
    from .motion_demo import motion_transfer_demo
    from .settings import AvatarLook, AvatarPlacement
    from .walk_target import replaced_person_demo

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    body = AnnyBody()
    model = load_model()
    paths: dict = {}

    logger.info("demo 1/7: generating the target clip (%d frames at %d²)", frames, size)
    sample = generate_sequence(SynthConfig(res=size, n_dirs=n_dirs), "test", DEMO_CLIP, frames, body=body)
    paths.update(_write_target(out, sample))

    logger.info("demo 2/7: avatar lit by the target's estimated light")
    res = avatar(paths["target"], out / "avatar.mp4", model=TorchPredictor(model), motion="walk",
                 look=AvatarLook(body=body), target_masks=paths["masks"],
                 placement=AvatarPlacement(plate=paths["plate"]), prt=PrtSettings(n_dirs=n_dirs), progress=progress)
    paths["avatar"], paths["avatar_lights"] = res.video, res.lights_file
    paths["side_by_side"] = write_side_by_side(out / "side_by_side.mp4", [paths["target"], res.video],
                                               sample.meta["fps"])
    true = torch.from_numpy(sample.arrays["light"])
    errors = {k: float(light_error(v, true)) for k, v in (("raw", res.lights_raw), ("smoothed", res.lights_smoothed))}
    png = light_curves_png(res.lights_raw, res.lights_smoothed, true, res.outliers, res.switches,
                           title=f"target light: raw error {errors['raw']:.3f}, smoothed {errors['smoothed']:.3f}")
    with atomic_write(out / "lights.png") as f:
        f.write(png)
    paths["lights_plot"] = out / "lights.png"

    logger.info("demo 3/7: the dressed avatar in place of a walking person (clean plate with a known truth)")
    replaced = replaced_person_demo(out / "replace", size, frames, body, n_dirs, progress=progress)
    paths.update({k: v for k, v in replaced.items() if isinstance(v, Path)})

    logger.info("demo 4/7: motion transfer: the avatar performs a generated person's walk in the target")
    moved = motion_transfer_demo(out / "motion", paths["target"], paths["masks"], paths["plate"], size, frames, body,
                                 TorchPredictor(model), n_dirs, sample.meta["fps"], progress)
    paths.update({k: v for k, v in moved.items() if isinstance(v, Path)})

    logger.info("demo 5/7: capture: a generated person captured under one light performs in the target")
    captured = capture_demo(out / "capture", paths["target"], paths["masks"], paths["plate"],
                            torch.from_numpy(sample.arrays["light"]), size, frames, body, TorchPredictor(model), n_dirs,
                            sample.meta["fps"], progress)
    paths.update({k: v for k, v in captured.items() if isinstance(v, Path)})

    logger.info("demo 6/7: 2D vs 3D comparison on %d generated sequences", compare_clips)
    paths["compare"] = _run_compare(out / "compare", body, compare_clips, compare_size, compare_frames,
                                    n_dirs, progress)

    logger.info("demo 7/7: preset light previews")
    paths["lights"] = render_presets(out / "lights", size=128)
    summary = {"target_clip": {"split": "test", "index": DEMO_CLIP, "frames": frames, "size": size,
                               "light": sample.meta["lights"]}, "light_error": errors,
               "replaced_person": {k: v for k, v in replaced.items() if not isinstance(v, Path)},
               "motion_transfer": {k: v for k, v in moved.items() if not isinstance(v, Path)},
               "capture": {k: v for k, v in captured.items() if not isinstance(v, Path)}}
    with atomic_write(out / "summary.json", "w") as f:
        f.write(json.dumps(summary, indent=1) + "\n")
    paths["summary"] = out / "summary.json"
    return paths


def _run_compare(out: Path, body, clips: int, size: int, frames: int, n_dirs: int, progress: bool) -> Path:
    """Generate ``clips`` test sequences (held-out env maps) and compare the 2D and 3D paths on them."""
    from ..data import SynthConfig
    from ..data.synth import run_synth
    from ..prt import PrtSettings
    from .compare import compare

    data = out.parent / "sequences"
    cfg = SynthConfig(seed=0, res=size, n_dirs=max(n_dirs, 64), shard_size=clips,
                      counts={"train": 0, "val": 0, "test": clips}, sequence_frames=frames)
    run_synth(data, cfg, workers=0, progress=progress, body=body)
    compare(data, out, split="test", prt=PrtSettings(n_dirs=n_dirs), progress=progress, body=body)
    return out
