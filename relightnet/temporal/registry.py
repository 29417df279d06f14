"""One registry of the light-smoothing methods: their names, options, where they run, and factories.

Every command that smooths a light sequence takes ``--smoothing NAME`` with a name from here,
and the library functions take the same names (``smoothing=``):

======================  =======  ======  ========  ===================================================
name                    offline  causal  evidence  what
======================  =======  ======  ========  ===================================================
``hermite``             yes      no      no        robust cubic Hermite spline (:func:`smooth_lights`)
``poly``                yes      no      no        polynomial regression, global or local
``savgol``              yes      no      no        Savitzky–Golay
``ema``                 yes      yes     no        exponential moving average (:class:`EMAFilter`)
``one-euro``            yes      yes     no        one-euro filter (:class:`OneEuroFilter`)
``fir``                 yes      yes     no        causal FIR (:class:`FIRFilter`)
``gated-one-euro``      yes      yes     no        outlier gate + one-euro (:class:`OutlierGate`)
``pooled``              yes      yes     yes       the light solve's evidence pooled per shot
``none``                yes      yes     no        the raw per-frame lights
======================  =======  ======  ========  ===================================================

*offline* methods smooth a whole recorded sequence (``avatar``, ``compare``, ``evaluate --light``,
``smooth-light``: :func:`smooth_sequence`); *causal* ones run frame by frame with explicit state
(``relight-video``, ``export``'s ONNX graph: :func:`make_smoother`, all ONNX-exportable).
``pooled`` needs the per-frame evidence of a network that solves its light
(:mod:`relightnet.temporal.pooling`). ``auto`` is ``pooled`` when there is evidence, else
``hermite`` offline and ``ema`` causally (:func:`resolve_smoothing`).

The video jobs accept :data:`VIDEO_SMOOTHING` (every name), the streaming ones
:data:`STREAMING_SMOOTHING` (the causal ones), ``smooth-light`` :data:`SEQUENCE_SMOOTHING` (those
that need no evidence).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from ..checks import InputError, sh_order_from_count
from ..names import SEQUENCE_SMOOTHING, STREAMING_SMOOTHING, VIDEO_SMOOTHING
from .causal import EMAFilter, FIRFilter, OneEuroFilter, run_causal
from .distance import light_distance
from .gate import OutlierGate
from .offline import SmoothResult, smooth_lights
from .pooling import PooledSolve, pool_shot_lights, pool_window

__all__ = ["SmoothingMethod", "SMOOTHING_METHODS", "VIDEO_SMOOTHING", "STREAMING_SMOOTHING", "SEQUENCE_SMOOTHING",
           "smoothing_names", "resolve_smoothing", "check_smoothing", "make_smoother", "smooth_sequence",
           "PassThrough"]


@dataclass(frozen=True)
class SmoothingMethod:
    """One smoothing method: ``offline`` (whole sequences), ``causal`` (streaming, ONNX-exportable),
    ``evidence`` (needs the light solve's evidence), its keyword ``options`` and a one-line ``summary``."""

    name: str
    offline: bool
    causal: bool
    evidence: bool
    options: tuple[str, ...]
    summary: str


#: Options every offline regression method takes (:func:`~relightnet.temporal.smooth_lights`).
_ROBUST = ("outlier_eps", "iterations", "switches", "switch_window", "switch_eps", "scale_window")
#: The gate's options (causal methods smoothed by :func:`smooth_sequence` with ``outlier_eps``).
_GATE = ("eps", "persist", "gamma", "init")

#: Every smoothing method by name (``auto`` is not one: :func:`resolve_smoothing` picks one).
SMOOTHING_METHODS: dict[str, SmoothingMethod] = {m.name: m for m in (
    SmoothingMethod("hermite", True, False, False, ("knot_spacing", "tangents", *_ROBUST),
                    "robust cubic Hermite spline with outlier correction and switch splitting"),
    SmoothingMethod("poly", True, False, False, ("degree", "window", *_ROBUST), "polynomial regression"),
    SmoothingMethod("savgol", True, False, False, ("window", "degree", *_ROBUST), "Savitzky-Golay"),
    SmoothingMethod("ema", True, True, False, ("alpha",), "exponential moving average"),
    SmoothingMethod("one-euro", True, True, False, ("min_cutoff", "beta", "d_cutoff", "rate", "normalize"),
                    "one-euro filter (cutoff rising with the light's speed)"),
    SmoothingMethod("fir", True, True, False, ("window", "degree", "taps"), "causal FIR filter"),
    SmoothingMethod("gated-one-euro", True, True, False, _GATE,
                    "causal outlier gate in front of a one-euro filter"),
    SmoothingMethod("pooled", True, True, True, ("alpha", "reg", "eps", "persist", "window"),
                    "the light solve's evidence pooled per shot (solve/hybrid networks)"),
    SmoothingMethod("none", True, True, False, (), "the raw per-frame lights"),
)}

def smoothing_names(causal: bool | None = None, evidence: bool | None = None) -> tuple[str, ...]:
    """Method names, optionally only the causal (or offline-only) ones, with or without evidence."""
    return tuple(n for n, m in SMOOTHING_METHODS.items()
                 if (causal is None or m.causal == causal) and (evidence is None or m.evidence == evidence))


def check_smoothing(name: str, allowed=VIDEO_SMOOTHING, what: str = "smoothing") -> str:
    """``name`` if it is one of ``allowed``, else an :class:`InputError` listing them."""
    if name not in allowed:
        raise InputError(f"{what}: expected one of {', '.join(allowed)}, got {name!r}")
    return name


def resolve_smoothing(name: str, has_evidence: bool, causal: bool = False) -> str:
    """The method ``name`` stands for: ``auto`` → ``pooled`` with evidence, else ``hermite``
    (offline) or ``ema`` (causal); ``pooled`` without evidence is refused."""
    if name == "auto":
        return "pooled" if has_evidence else ("ema" if causal else "hermite")
    if name not in SMOOTHING_METHODS:
        raise InputError(f"smoothing: expected auto or one of {', '.join(SMOOTHING_METHODS)}, got {name!r}")
    if SMOOTHING_METHODS[name].evidence and not has_evidence:
        raise InputError(f"smoothing {name}: the model regresses its light (no solve to pool); use another method")
    if causal and not SMOOTHING_METHODS[name].causal:
        raise InputError(f"smoothing {name}: an offline method; streaming takes one of "
                         f"{', '.join(smoothing_names(causal=True))}")
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
            ``reg`` the network's λ, sliding window of :func:`~relightnet.temporal.pool_window` at ``fps``
            unless ``window=`` is given).
        gate: for a causal method, the options of an :class:`~relightnet.temporal.gate.OutlierGate`
            put in front of it (``eps``, ``persist``, ...); its status gives the outliers and switches.
        **opts: the method's options; the offline regressions take ``outlier_eps``, ``switches``, ...
            (:func:`~relightnet.temporal.smooth_lights`).

    Returns:
        :class:`~relightnet.temporal.SmoothResult` ``(smoothed (T, K, 3), outliers (T,), distances
        (T,), switches (T,))``.
    """
    name = resolve_smoothing(method, evidence is not None)
    _check_options(name, opts)
    none = torch.zeros(lights.shape[0], dtype=torch.bool)
    if name == "pooled":
        window = opts.pop("window", pool_window(fps))
        smoothed, _, switches = pool_shot_lights(evidence, prior, reg, window=window)
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
