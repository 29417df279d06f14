"""The names a user types — presets, methods, modes — in one module that imports nothing heavy.

The command line lists these names in its ``--help`` without importing torch (so ``--help``
answers at once), and the library modules that implement each name take their list from
here, so a name exists in one place. ``tests/test_names.py`` checks that every name listed
here is implemented where it is used.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "MASK_SOURCES",
    "MOTION_KINDS",
    "OFFLINE_METHODS",
    "LIGHT_FROM",
    "LIGHT_WORD_KINDS",
    "OUTFITS",
    "POSE_PRESETS",
    "SEQUENCE_SMOOTHING",
    "SMOOTHING_METHODS",
    "STREAMING_SMOOTHING",
    "SmoothingMethod",
    "VIDEO_SMOOTHING",
    "envmap_dir",
    "light_presets",
    "smoothing_help",
    "smoothing_names",
]


@dataclass(frozen=True)
class SmoothingMethod:
    """One light-smoothing method: ``causal`` (runs frame by frame with explicit state: streaming,
    ONNX-exportable; every method also smooths a whole recorded sequence), ``evidence`` (needs the
    light solve's evidence), its keyword ``options`` and a one-line ``summary``."""

    name: str
    causal: bool
    evidence: bool
    options: tuple[str, ...]
    summary: str


#: Options every offline regression method takes (:func:`relightnet.temporal.smooth_lights`).
_ROBUST = ("outlier_eps", "iterations", "switches", "switch_window", "switch_eps", "scale_window")

#: The one table of the light-smoothing methods, by name (``auto`` is not one: it stands for
#: ``pooled`` with evidence, else ``hermite`` offline or ``ema`` streaming). Every list below and
#: every ``--smoothing`` help is derived from it; :mod:`relightnet.temporal.registry` implements it.
SMOOTHING_METHODS: dict[str, SmoothingMethod] = {m.name: m for m in (
    SmoothingMethod("pooled", True, True, ("alpha", "reg", "eps", "persist", "window"),
                    "the light solve's evidence pooled per shot (solve/hybrid networks)"),
    SmoothingMethod("hermite", False, False, ("knot_spacing", "tangents", *_ROBUST),
                    "robust cubic Hermite spline with outlier correction and switch splitting"),
    SmoothingMethod("poly", False, False, ("degree", "window", *_ROBUST), "polynomial regression"),
    SmoothingMethod("savgol", False, False, ("window", "degree", *_ROBUST), "Savitzky-Golay"),
    SmoothingMethod("ema", True, False, ("alpha",), "exponential moving average"),
    SmoothingMethod("one-euro", True, False, ("min_cutoff", "beta", "d_cutoff", "rate", "normalize"),
                    "one-euro filter (cutoff rising with the light's speed)"),
    SmoothingMethod("fir", True, False, ("window", "degree", "taps"), "causal FIR filter"),
    SmoothingMethod("gated-one-euro", True, False, ("eps", "persist", "gamma", "init"),
                    "causal outlier gate in front of a one-euro filter"),
    SmoothingMethod("none", True, False, (), "the raw per-frame lights"),
)}


def smoothing_names(causal: bool | None = None, evidence: bool | None = None) -> tuple[str, ...]:
    """Method names in table order, optionally only the causal (or offline-only) ones, with or without evidence."""
    return tuple(n for n, m in SMOOTHING_METHODS.items()
                 if (causal is None or m.causal == causal) and (evidence is None or m.evidence == evidence))


#: Offline-only regressions of a whole light sequence (:func:`relightnet.temporal.smoothing_matrix`).
OFFLINE_METHODS = smoothing_names(causal=False)
#: Light smoothing of the offline video jobs (avatar, compare, evaluate light): ``auto`` or any method.
VIDEO_SMOOTHING = ("auto", *SMOOTHING_METHODS)
#: Light smoothing of the streaming jobs (relight-video, export, onnx-run): ``auto`` (``pooled`` with
#: the light solve's evidence, else ``ema``) or a causal method (each can live inside an ONNX graph).
STREAMING_SMOOTHING = ("auto", *smoothing_names(causal=True))
#: Light smoothing of a recorded light file (smooth-light): every method that needs no evidence.
SEQUENCE_SMOOTHING = smoothing_names(evidence=False)


def smoothing_help(allowed: tuple[str, ...], default: str) -> str:
    """The ``--smoothing`` help of a command that takes ``allowed`` (one line per name, from the table)."""
    auto = {"auto": "pooled when the network solves its light, else "
                    + ("ema" if set(allowed) <= {"auto", *smoothing_names(causal=True)} else "hermite")}
    parts = [f"{n}: {auto[n] if n == 'auto' else SMOOTHING_METHODS[n].summary}" for n in allowed]
    return "light smoothing over time; " + "; ".join(parts) + f" (default: {default})"


#: The terms of a light written in words (:mod:`relightnet.light.words`): disc lights under a name
#: that says their role (all behave alike) and a constant ``ambient``.
LIGHT_WORD_KINDS = ("key", "fill", "rim", "light", "ambient")
#: Where the avatar's light comes from: the background plate, the person in the target, or both.
LIGHT_FROM = ("person", "plate", "both")

#: Where a person's mask comes from when none is given: the shipped segmentation or the CNN's mask head.
MASK_SOURCES = ("segment", "head")

#: Still-pose presets of the Anny body (:data:`relightnet.body.anny_model.POSE_PRESETS` holds the rotations).
POSE_PRESETS = ("rest", "tpose", "apose", "arms_down", "arms_crossed")
#: Procedural motions of the Anny body (:func:`relightnet.body.make_motion`).
MOTION_KINDS = ("walk", "turn", "idle", "arm_raise")
#: Named outfits of the dressed avatar (:data:`relightnet.pipeline.outfits.OUTFIT_SLOTS`); also ``random:SEED``.
OUTFITS = ("casual", "dress", "jacket", "coat", "skirt", "hood")


def envmap_dir() -> Path:
    """The folder of the shipped environment maps (``relightnet/data/envmaps``)."""
    return Path(__file__).resolve().parent / "data" / "envmaps"


def light_presets() -> list[str]:
    """Sorted names of the shipped light presets: the file stems of ``relightnet/data/envmaps/*.exr``."""
    return sorted(p.stem for p in envmap_dir().glob("*.exr"))
