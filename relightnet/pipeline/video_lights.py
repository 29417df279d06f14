"""The light of a video, the first stages of the video jobs: estimate per frame → smooth over time.

:func:`estimate_video_evidence` runs the CNN on every frame (streaming) and keeps what a video
needs (the per-frame lights, and for a network that solves its light the solve's evidence and
priors); :func:`relightnet.temporal.smooth_video_lights` smooths them. ``avatar``, ``compare``
and ``evaluate light`` use both.

The estimates of ``avatar`` are kept in its side file ``OUT.lights.npz``
(:func:`write_video_lights`) with a fingerprint of the inputs (:func:`lights_fingerprint`): when
it matches, a rerun reuses them (:func:`read_light_estimates`) instead of running the CNN again.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import NamedTuple

import numpy as np
import torch

from ..checks import InputError
from .backends import as_predictor

__all__ = ["VideoEstimates", "estimate_video_lights", "estimate_video_evidence", "lights_fingerprint",
           "read_light_estimates", "write_video_lights"]


class VideoEstimates(NamedTuple):
    """What the light pass of a video keeps per frame.

    Attributes:
        raw: (T, K, 3) the CNN's lights (camera-relative light frame, linear RGB).
        evidence: the light solve's :class:`~relightnet.sh.light_solve.Evidence` (``M`` (T, 3, K, K),
            ``r`` (T, 3, K)), None for a network that regresses its light.
        prior: (T, K, 3) the hybrid's priors, or None.
        colour: (T, 3) float64 each frame's mean linear colour (:func:`~relightnet.temporal.frame_colour`:
            the light switches seen in the frames), or None.
    """

    raw: torch.Tensor
    evidence: object = None
    prior: torch.Tensor | None = None
    colour: torch.Tensor | None = None


@torch.no_grad()
def estimate_video_lights(model, video, masks=None, progress: bool = True, mask_source: str = "segment"
                          ) -> torch.Tensor:
    """Per-frame light estimates of a video (the first pass of ``avatar``).

    Args:
        model: a :class:`~relightnet.model.RelightNet` or a predictor (:mod:`.backends`).
        video: the target video file.
        masks: folder of mask images or a mask video (one per frame), or None: ``mask_source``
            (``segment``: the person segmentation; ``head``: the model's mask head).

    Returns:
        (T, K, 3) raw lights, camera-relative light frame, linear RGB.
    """
    return estimate_video_evidence(model, video, masks, progress, mask_source)[0]


@torch.no_grad()
def estimate_video_evidence(model, video, masks=None, progress: bool = True, mask_source: str = "segment"):
    """Per-frame lights of a video with the light solve's evidence (for pooling over shots).

    Same arguments as :func:`estimate_video_lights`.

    Returns:
        :class:`VideoEstimates` ``(raw (T, K, 3), evidence, prior, colour (T, 3))``.
    """
    from tqdm import tqdm

    from ..segment.sources import video_masks
    from ..sh.light_solve import stack_evidence
    from ..temporal.switches import frame_colour

    predict = as_predictor(model)
    if masks is None and mask_source == "head" and not predict.has_mask_head:
        raise InputError("--mask-source head: this model has no mask head; give --target-masks or use 'segment'")
    _, n_frames, frames = video_masks(video, masks, mask_source)
    lights, evs, priors, colours = [], [], [], []
    for _, img, mask in tqdm(frames, total=n_frames or None, desc="estimate light",
                             unit="frame", disable=not progress):
        light, ev, prior = predict.light_evidence(img, mask)
        lights.append(light.float().cpu())
        evs.append(ev)
        priors.append(prior)
        colours.append(frame_colour(img))
    if not lights:
        raise InputError(f"{video}: the video has no frames")
    return VideoEstimates(torch.stack(lights), *stack_evidence(evs, priors), torch.stack(colours))


def lights_fingerprint(video, masks, predictor_name: str, mask_source: str = "segment") -> str:
    """What the light estimates of a video depend on: the video's and masks' names, sizes and
    modification times, and the model's name (a JSON string)."""
    def stat(p):
        p = Path(p)
        if p.is_dir():
            return sorted((f.name, f.stat().st_size, f.stat().st_mtime_ns) for f in p.iterdir())
        st = p.stat()
        return [p.name, st.st_size, st.st_mtime_ns]

    return json.dumps({"video": stat(video), "masks": mask_source if masks is None else stat(masks),
                       "model": predictor_name}, sort_keys=True)


def read_light_estimates(path: Path, fingerprint: str) -> VideoEstimates | None:
    """The :class:`VideoEstimates` saved by an earlier run with the same inputs, or None (no file,
    another fingerprint, a damaged or foreign file, one without the frames' colours: it is then
    rewritten)."""
    from ..io.arrays import read_npz
    from ..sh.light_solve import Evidence

    if not path.is_file():
        return None
    try:
        z = read_npz(path, "light estimates", ("fingerprint", "raw", "colour", "evidence_M", "evidence_r", "prior"))
    except InputError:
        return None
    if not ("raw" in z and "fingerprint" in z and z["fingerprint"].size == 1 and str(z["fingerprint"]) == fingerprint
            and z["raw"].dtype.kind == "f" and z["raw"].ndim == 3 and "colour" in z):
        return None
    raw = torch.from_numpy(z["raw"])
    t, k = raw.shape[:2]
    if z["colour"].shape != (t, 3) or z["colour"].dtype.kind != "f":
        return None
    ev = prior = None
    if "evidence_M" in z and "evidence_r" in z:
        M, r = z["evidence_M"], z["evidence_r"]
        if M.shape != (t, 3, k, k) or r.shape != (t, 3, k) or M.dtype.kind != "f" or r.dtype.kind != "f":
            return None
        ev = Evidence(torch.from_numpy(M), torch.from_numpy(r))
    if "prior" in z:
        if z["prior"].shape != raw.shape or z["prior"].dtype.kind != "f":
            return None
        prior = torch.from_numpy(z["prior"])
    return VideoEstimates(raw, ev, prior, torch.from_numpy(z["colour"]))


def write_video_lights(lights_file: Path, plot: Path, smoothed: torch.Tensor, fingerprint: str,
                       estimates: VideoEstimates | None = None, outliers=None, switches=None, smoothing: str = "",
                       title: str = "") -> None:
    """Write a video job's light side files atomically: ``lights_file`` in the light-sequence
    format (:func:`relightnet.sh.save_light_sequence`: ``sh`` = ``smoothed`` (T, K, 3), the light
    of each frame, readable by ``smooth-light``; side arrays ``smoothed``, ``fingerprint``, and with
    ``estimates`` (:class:`VideoEstimates`) ``raw``, ``outliers`` and ``switches`` ((T,) bool),
    ``smoothing``, ``colour``, ``evidence_M``/``evidence_r``, ``prior``) and ``plot`` (light
    curves, PNG); the folder is made if needed."""
    from ..io import atomic_write
    from ..sh.io import save_light_sequence
    from ..temporal.plot import light_curves_png

    n = smoothed.shape[0]
    lights_file.parent.mkdir(parents=True, exist_ok=True)
    arrays = {"smoothed": smoothed.numpy(), "fingerprint": np.array(fingerprint)}
    raw = None if estimates is None else estimates.raw
    if estimates is not None:
        arrays.update(raw=raw.numpy(), outliers=outliers.numpy(), switches=switches.numpy(),
                      smoothing=np.array(smoothing))
        optional = {"colour": estimates.colour, "prior": estimates.prior,
                    **({} if estimates.evidence is None else {"evidence_M": estimates.evidence[0],
                                                              "evidence_r": estimates.evidence[1]})}
        arrays.update({k: v.numpy() for k, v in optional.items() if v is not None})
    save_light_sequence(lights_file, smoothed, **arrays)
    png = light_curves_png(raw[:n] if raw is not None else None, smoothed,
                           outliers=outliers[:n] if outliers is not None else None,
                           switches=switches[:n] if switches is not None else None, title=title)
    with atomic_write(plot) as f:
        f.write(png)
