"""The light-smoothing methods implemented: resolving a name, building a filter, smoothing a sequence.

The methods — names, whether they are causal or need the light solve's evidence, their options
and one-line summaries — are one torch-free table, :data:`relightnet.names.SMOOTHING_METHODS`;
every list a command accepts and every ``--smoothing`` help is derived from it. Every method
smooths a whole recorded sequence (``smooth-light``: :func:`smooth_sequence`; the offline video
jobs ``avatar``, ``compare``, ``evaluate light``: :func:`smooth_video_lights`, which resolves
the name once and returns the method used); the *causal* ones also run frame by frame with
explicit state (``relight-video``, ``export``'s ONNX graph: :func:`make_smoother`).
``pooled`` needs the per-frame evidence of a network that solves its light
(:mod:`relightnet.temporal.pooling`). ``auto`` is ``pooled`` when there is evidence, else
``hermite`` offline and ``ema`` causally (:func:`resolve_smoothing`).
"""

from __future__ import annotations

import logging
from typing import NamedTuple

import torch
from torch import nn

from ..checks import InputError, check_shape, sh_order_from_count
from ..names import SMOOTHING_METHODS, VIDEO_SMOOTHING, smoothing_names
from .causal import EMAFilter, FIRFilter, OneEuroFilter, run_causal
from .distance import light_distance
from .gate import OutlierGate
from .offline import SmoothResult, detect_switches, smooth_lights
from .pooling import PooledSolve, pool_shot_lights, pool_window
from .switches import colour_switches, merge_switches

__all__ = ["resolve_smoothing", "check_smoothing", "make_smoother", "smooth_sequence", "smooth_video_lights",
           "VideoSmoothing", "PassThrough", "MIN_FIT_FRAMES"]

logger = logging.getLogger("relightnet.temporal")

#: The fewest frames an offline regression fits; a shorter clip keeps its raw lights (``none``).
MIN_FIT_FRAMES = 3


def check_smoothing(name: str, allowed=VIDEO_SMOOTHING, what: str = "smoothing") -> str:
    """``name`` if it is one of ``allowed``, else an :class:`InputError` listing them."""
    if name not in allowed:
        raise InputError(f"{what}: expected one of {', '.join(allowed)}, got {name!r}")
    return name


def resolve_smoothing(name: str, has_evidence: bool, causal: bool = False, frames: int | None = None) -> str:
    """The method ``name`` stands for: ``auto`` → ``pooled`` with evidence, else ``hermite``
    (offline) or ``ema`` (causal); ``pooled`` without evidence is refused. With ``frames`` (the
    length of a recorded sequence), an offline regression of fewer than :data:`MIN_FIT_FRAMES`
    frames becomes ``none`` (the raw lights), with a warning."""
    if name == "auto":
        name = "pooled" if has_evidence else ("ema" if causal else "hermite")
    elif name not in SMOOTHING_METHODS:
        raise InputError(f"smoothing: expected auto or one of {', '.join(SMOOTHING_METHODS)}, got {name!r}")
    if SMOOTHING_METHODS[name].evidence and not has_evidence:
        raise InputError(f"smoothing {name}: the model regresses its light (no solve to pool); use another method")
    if causal and not SMOOTHING_METHODS[name].causal:
        raise InputError(f"smoothing {name}: an offline method; streaming takes one of "
                         f"{', '.join(smoothing_names(causal=True))}")
    if frames is not None and frames < MIN_FIT_FRAMES and not SMOOTHING_METHODS[name].causal:
        logger.warning("smoothing %s: %d frame(s) are too few to fit (at least %d); the raw lights are used "
                       "(smoothing none)", name, frames, MIN_FIT_FRAMES)
        return "none"
    return name


def _check_options(name: str, opts: dict) -> None:
    bad = sorted(set(opts) - set(SMOOTHING_METHODS[name].options))
    if bad:
        allowed = ", ".join(SMOOTHING_METHODS[name].options) or "none"
        raise InputError(f"smoothing {name}: unknown option(s) {', '.join(bad)}; it takes {allowed}")


class PassThrough(nn.Module):
    """No smoothing: y = x (state kept as the last raw light)."""

    state_size = 1

    def forward(self, x: torch.Tensor, state: torch.Tensor | None = None, is_first: torch.Tensor | None = None):
        return x, x[:, None]


def make_smoother(name: str, lmax: int = 2, **opts) -> nn.Module:
    """A causal smoother module by name: ``forward(x (B, K, 3), state, is_first) -> (y, state)``
    (:mod:`relightnet.temporal.causal`); ``pooled`` also takes ``evidence=``, ``prior=``.

    Args:
        name: a causal method (``none``, ``ema``, ``one-euro``, ``fir``, ``gated-one-euro``, ``pooled``).
        lmax: SH order of the lights it will filter.
        **opts: the method's options (:attr:`SmoothingMethod.options`).
    """
    if name not in SMOOTHING_METHODS or not SMOOTHING_METHODS[name].causal:
        raise InputError(f"smoothing: expected one of {', '.join(smoothing_names(causal=True))}, got {name!r}")
    opts = {k: v for k, v in opts.items() if not (name == "pooled" and k == "window")}
    _check_options(name, opts)
    if name == "none":
        return PassThrough()
    if name == "ema":
        return EMAFilter(**opts)
    if name == "fir":
        return FIRFilter(**opts)
    if name == "one-euro":
        return OneEuroFilter(lmax=lmax, **opts)
    if name == "gated-one-euro":
        return OutlierGate(OneEuroFilter(lmax=lmax), lmax=lmax, **opts)
    return PooledSolve(lmax=lmax, **opts)


def smooth_sequence(lights: torch.Tensor, method: str = "auto", evidence=None, prior=None, reg: float = 1e-2,
                    fps: float = 30.0, gate: dict | None = None, **opts):
    """Smooth a recorded (T, K, 3) light sequence with any method of the registry.

    Args:
        lights: (T, K, 3) per-frame lights.
        method: a method name or ``auto`` (:func:`resolve_smoothing`).
        evidence, prior: the light solve's per-frame evidence (``M`` (T, 3, K, K), ``r`` (T, 3, K))
            and priors (T, K, 3), for ``pooled`` (:func:`~relightnet.temporal.pool_shot_lights`,
            ``reg`` the network's λ: one light per segment, a segment whose light changes pooled over
            the window of :func:`~relightnet.temporal.pooling.pool_window` at ``fps``; ``window=`` frames: a
            sliding window everywhere).
        gate: for a causal method, the options of an :class:`~relightnet.temporal.gate.OutlierGate`
            put in front of it (``eps``, ``persist``, ...); its status gives the outliers and switches.
        **opts: the method's options; the offline regressions take ``outlier_eps``, ``switches``, ...
            (:func:`~relightnet.temporal.smooth_lights`).

    Returns:
        :class:`~relightnet.temporal.SmoothResult` ``(smoothed (T, K, 3), outliers (T,), distances
        (T,), switches (T,))``.
    """
    return _smooth(lights, resolve_smoothing(method, evidence is not None), evidence, prior, reg, fps, gate, **opts)


def _smooth(lights, name, evidence, prior, reg, fps, gate, colour=None, **opts):
    """:func:`smooth_sequence` with a resolved method name (``colour``: the frames' colours, for switches)."""
    _check_options(name, opts)
    none = torch.zeros(lights.shape[0], dtype=torch.bool)
    if name == "pooled":
        # One light per segment, a changing segment's pooled over the window; ``window=`` slides it everywhere.
        window = opts.pop("window", None)
        smoothed, _, switches = pool_shot_lights(evidence, prior, reg, window=window, change_window=pool_window(fps),
                                                 colour=colour)
        return SmoothResult(smoothed, none, light_distance(lights, smoothed.to(lights)), switches)
    if name == "none":
        return SmoothResult(lights.clone(), none, torch.zeros(lights.shape[0], dtype=lights.dtype), none)
    if not SMOOTHING_METHODS[name].causal:
        return smooth_lights(lights, name, **opts)
    lmax = sh_order_from_count(lights.shape[-2], "lights")
    filt = make_smoother(name, lmax, **opts)
    if gate is None:
        y = run_causal(filt, lights)
        return SmoothResult(y, none, light_distance(lights, y), none)
    y, states = run_causal(OutlierGate(filt, lmax=lmax, **gate), lights, return_states=True)
    status = states[:, -1, 0, 0].round()
    return SmoothResult(y, status == 1, light_distance(lights, y), status == 2)


class VideoSmoothing(NamedTuple):
    """What :func:`smooth_video_lights` returns: ``smoothed`` (T, K, 3), ``outliers`` and ``switches``
    (T,) bool, and ``method``, the method actually used (``auto`` resolved, short clips ``none``)."""

    smoothed: torch.Tensor
    outliers: torch.Tensor
    switches: torch.Tensor
    method: str


def smooth_video_lights(raw: torch.Tensor, method: str = "auto", evidence=None, prior=None, reg: float = 1e-2,
                        fps: float = 30.0, colour: torch.Tensor | None = None) -> VideoSmoothing:
    """Smooth a video's (T, K, 3) per-frame lights the way every offline video job does
    (``avatar``, ``compare``, ``evaluate light``); the method is resolved here, once.

    ``method`` is ``auto`` or any method of :data:`relightnet.names.SMOOTHING_METHODS`.
    ``pooled`` shares the light across frames: the per-frame evidence of the light solve
    (``evidence``, ``prior``: ``M`` (T, 3, K, K), ``r`` (T, 3, K), (T, K, 3); ``reg`` the network's
    λ) of all the frames between the same detected light switches is solved jointly, one light per
    segment — unless the segment's light changes (:func:`~relightnet.temporal.changing_segments`),
    then over the frames within :data:`~relightnet.temporal.pooling.POOL_SECONDS` (triangular
    weights, at the video's ``fps``);
    ``hermite``/``poly``/``savgol`` are robust regressions with 3-MAD outlier correction and
    automatic switch detection (fewer than :data:`MIN_FIT_FRAMES` frames: the raw lights, with a
    warning, and ``none`` is the method returned); the causal filters run over the sequence with
    their default options; ``auto`` is ``pooled`` when there is evidence, else ``hermite``.
    ``colour`` (T, 3), the frames' mean linear colours (:func:`~relightnet.temporal.frame_colour`),
    adds the steps of the frames' colour to the switches of ``pooled`` and the regressions
    (:func:`~relightnet.temporal.colour_switches`).

    Returns:
        :class:`VideoSmoothing` ``(smoothed (T, K, 3), outliers (T,), switches (T,), method)``.
    """
    name = resolve_smoothing(method, evidence is not None, frames=raw.shape[0])  # checks the name too
    robust = not SMOOTHING_METHODS[name].causal
    opts = {"outlier_eps": "3mad", "switches": "auto"} if robust else {}
    if robust and colour is not None:
        check_shape(colour, [raw.shape[0], "C"], name="frame colours")
        opts["switches"] = merge_switches(detect_switches(raw.double()), colour_switches(colour))
    res = _smooth(raw, name, evidence, prior, reg, fps, None, colour=colour, **opts)
    return VideoSmoothing(res.smoothed, res.outliers, res.switches, name)
