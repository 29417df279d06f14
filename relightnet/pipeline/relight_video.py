"""Job 2 of the pipeline: relight a video of a person frame by frame (2D path), streaming.

Frames and masks are read one at a time and the output is written as it goes, so memory
does not depend on the video's length. The light estimated from each source frame is
smoothed causally before it sets the exposure reference, so the relit person does not
flicker with the per-frame estimate. ``smoothing`` names a causal method of
:mod:`relightnet.temporal.registry`; by default (``auto``) a network that solves its light pools
the solve's evidence since the last light switch (:class:`relightnet.temporal.PooledSolve`: under a
constant light the estimate settles instead of following each frame), one that regresses it
is smoothed by an EMA (weight ``alpha``); the new light can turn about the up axis over time.
As for photos, the albedo relit is the frame divided by the predicted shading, so the
frames keep their detail. Each frame is relit at its full size in bands of rows
(:func:`~relightnet.pipeline.relight_bands.relight_over_photo`): the CNN's maps are never held
at the frame's size, so a frame at the pixel limit stays within the memory budget.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import torch

from ..checks import InputError
from ..io import VideoWriter
from ..io.hdr_video import HdrClip, HdrVideoWriter
from ..io.video import frame_times
from ..names import STREAMING_SMOOTHING
from ..segment.sources import video_masks
from ..sh import rotate_sh_up
from ..temporal.registry import check_smoothing, make_smoother, resolve_smoothing
from .backends import as_predictor
from .relight_bands import relight_over_photo
from .relight_image import to_model_order
from .settings import VideoLightSettings
from .steady_maps import MapCarry

logger = logging.getLogger(__name__)

__all__ = ["NO_PERSON_S", "PERSON_SHARE", "person_in_most", "relight_video"]

#: Seconds at the start of a segmented video in most of whose frames a person must be found, else it is
#: refused then (a clip of nobody fails in seconds, not after all its frames).
NO_PERSON_S = 2.0
#: The least share of a frame a mask covers for the frame to count as showing a person.
PERSON_SHARE = 0.005


def person_in_most(shares, min_share: float = PERSON_SHARE) -> bool:
    """Whether more than half of the frames show a person: ``shares`` (T,) the share of each frame
    its mask covers, each counted when at least ``min_share`` (a few frames of a segmentation's
    false positives on a clip of nobody do not count as a person)."""
    shares = list(shares)
    return 2 * sum(float(s) >= min_share for s in shares) > len(shares)


@torch.no_grad()
def relight_video(model, video, masks, light: torch.Tensor, out, turntable_deg_per_s: float = 0.0,
                  lights: VideoLightSettings = VideoLightSettings(), progress: bool = True, detail: bool = True,
                  soft_edges: bool = True, steady: bool = True, hdr: bool = False) -> int:
    """Relight every frame of ``video`` with ``light`` and write ``out`` (mp4/mkv).

    Args:
        model: the CNN: a :class:`RelightNet` or a predictor (:mod:`relightnet.pipeline.backends`).
        video: input video file (its frames' times and its sound, if any, are kept in ``out``:
            a variable frame rate stays so; :mod:`relightnet.io.timestamps`).
        masks: folder of per-frame mask images (sorted) or a mask video, one per frame, or None
            (``lights.mask_source``: the person segmentation, or the CNN's mask head); a frame whose mask
            is empty (the person out of view) is written unchanged; segmented, a video with nobody
            in its first :data:`NO_PERSON_S` seconds is refused then.
        light: (K, 3) new light (camera-relative light frame).
        out: output video path (written atomically).
        turntable_deg_per_s: turn the new light about the up axis at this rate.
        lights: a :class:`~relightnet.pipeline.VideoLightSettings`: ``smoothing``, how the source-light
            estimate is smoothed, a causal method (:data:`~relightnet.names.STREAMING_SMOOTHING`: ``auto``,
            ``pooled``, ``ema``, ``one-euro``, ``fir``, ``gated-one-euro``, ``none``); ``mask_source``, without
            ``masks``: ``segment`` or ``head`` (:mod:`relightnet.segment.sources`); ``alpha``, ``ema``'s
            weight of the newest frame, in (0, 1].
        detail: relight each frame's own albedo (frame / predicted shading under the smoothed
            source light; :func:`~relightnet.model.photo_albedo`); False relights the CNN's albedo.
        soft_edges: each frame's person composited with a soft matte in its border band
            (:func:`~relightnet.segment.matte.soft_composite`); False pastes with the mask as it is.
        steady: carry the CNN's maps from frame to frame along the optical flow
            (:class:`~relightnet.pipeline.steady_maps.MapCarry`), so the relit person does not flicker more
            than the footage; False relights every frame from its own prediction alone.
        hdr: keep an HLG or PQ video HDR (:class:`~relightnet.io.hdr_video.HdrClip`; an SDR one is refused
            before any work); False writes the frames tone-mapped to SDR, as they are read.

    Returns:
        The number of frames written.
    """
    from tqdm import tqdm

    if not math.isfinite(turntable_deg_per_s) or abs(turntable_deg_per_s) > 1e6:
        raise InputError(f"turntable: expected degrees per second (a finite number), got {turntable_deg_per_s}")
    mask_source = lights.mask_source
    check_smoothing(lights.smoothing, STREAMING_SMOOTHING)  # the EMA weight: checked by VideoLightSettings
    smoothing, alpha = lights.smoothing, float(lights.alpha)
    predict = as_predictor(model)
    if masks is None and mask_source == "head" and not predict.has_mask_head:
        raise InputError("--mask-source head: this model has no mask head; give --masks or use 'segment'")
    info, n_masks, pairs = video_masks(video, masks, mask_source, allow_empty=True)
    # Segmented (no masks given): a clip with nobody in its first seconds is refused then, not at its end.
    gate = _person_gate(video, info.fps) if masks is None and mask_source == "segment" else None
    times = frame_times(video)  # None: the file states no times, the frames follow at its average rate
    clip = HdrClip(video) if hdr else None  # an SDR video is refused here, before any work
    relight = _FrameRelighter(predict, to_model_order(light, predict.lmax), turntable_deg_per_s, smoothing, alpha,
                              MapCarry() if steady else None, detail=detail, soft_edges=soft_edges,
                              dtype=torch.uint8 if clip is None else torch.float32)
    n = 0
    empty: list[int] = []
    with (VideoWriter(out, fps=info.fps, srgb=False, audio_from=video) if clip is None else
          HdrVideoWriter(out, clip.fmt, fps=info.fps, audio_from=video)) as writer:
        for t, img, mask in tqdm(pairs, total=n_masks or None, desc="relight-video", unit="frame",
                                 disable=not progress):
            time = float(times[t]) if times is not None and t < len(times) else None
            if gate is not None:
                gate(t, mask)
            if mask is not None and not mask.any():  # the person is out of the frame: nothing to relight
                writer.write(img.permute(1, 2, 0) if clip is None else clip.carry(img, img), time=time)
                empty.append(t)
                relight.lost()
            else:
                elapsed = t / info.fps if time is None else time - float(times[0])
                try:
                    relit = relight(img, mask, elapsed)
                    writer.write(relit if clip is None else clip.carry(relit, img), time=time)
                except InputError as e:  # a frame the CNN cannot take (e.g. blank, for its mask head): name it
                    raise InputError(f"{video}: frame {t}: {e}") from None
            del img, mask  # the next frame is decoded and predicted without this one's
            n += 1
        if n and len(empty) == n:  # raised inside the writer's block: no output is left
            raise InputError(f"{masks or video}: every mask is empty: no person to relight")
    if empty:
        logger.warning("%d frame(s) with an empty mask were written unchanged (first: frame %d)", len(empty), empty[0])
    logger.info("wrote %s (%d frames)", Path(out), n)
    return n


class _FrameRelighter:
    """One frame of :func:`relight_video` at a time: the CNN's maps (carried along the flow by ``carry``,
    :class:`~relightnet.pipeline.steady_maps.MapCarry`, or None), the source light smoothed causally, the
    new light turned by the turntable, the frame relit → (H, W, 3) uint8. :meth:`lost`: a frame without
    the person (the carry starts afresh after it; the light's smoothing goes on)."""

    def __init__(self, predict, light: torch.Tensor, turntable_deg_per_s: float, smoothing: str, alpha: float,
                 carry, detail: bool, soft_edges: bool, dtype: torch.dtype = torch.uint8) -> None:
        self.predict, self.light, self.turn = predict, light, math.radians(turntable_deg_per_s)
        self.smoothing, self.alpha, self.carry = smoothing, alpha, carry
        self.detail, self.soft_edges, self.dtype = detail, soft_edges, dtype
        self.smoother = self.state = None

    def lost(self) -> None:
        if self.carry is not None:
            self.carry.reset()

    def __call__(self, img: torch.Tensor, mask: torch.Tensor | None, elapsed: float) -> torch.Tensor:
        pred = self.predict.crop(img, mask)  # the maps stay at the working size: pasted band by band
        if self.carry is not None:
            pred = self.carry(img, pred)
        if self.smoother is None:  # auto: pooled or ema, whether the network solves its light
            self.smoother = _smoother(self.smoothing, pred.evidence is not None, self.predict, self.alpha)
        kw = {"evidence": pred.evidence, "prior": pred.light_head} \
            if getattr(self.smoother, "uses_evidence", False) else {}
        y, self.state = self.smoother(pred.light, self.state, torch.tensor([self.state is None]), **kw)
        new = rotate_sh_up(self.light, self.turn * elapsed)
        # Exposure reference and photo albedo: the smoothed source light, not this frame's raw estimate.
        return relight_over_photo(pred, img, new, detail=self.detail, reference=y[0], dtype=self.dtype,
                                  soft_edges=self.soft_edges).image


def _person_gate(video, fps: float):
    """A check called with each frame's ``(t, mask)``: raises once the first :data:`NO_PERSON_S` seconds
    are seen and most of them show nobody (:func:`person_in_most`)."""
    give_up = math.ceil(NO_PERSON_S * fps)
    shares: list[float] = []

    def gate(t: int, mask: torch.Tensor) -> None:
        if t >= give_up:
            return
        shares.append(float(mask.float().mean()))
        if t == give_up - 1 and not person_in_most(shares):
            raise InputError(f"{video}: no person found in most of its first {NO_PERSON_S:g} s (frames 0-{t}); "
                             "expected a video showing a person (give --masks if they enter later)")
    return gate


def _smoother(smoothing: str, has_evidence: bool, predict, alpha: float):
    """The causal smoother of the source light (:func:`relightnet.temporal.make_smoother`)."""
    name = resolve_smoothing(smoothing, has_evidence, causal=True)
    opts = {"ema": {"alpha": alpha}, "pooled": {"reg": predict.solve_reg}}.get(name, {})
    return make_smoother(name, predict.lmax, **opts)
