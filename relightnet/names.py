"""The names a user types — presets, methods, modes — in one module that imports nothing heavy.

The command line lists these names in its ``--help`` without importing torch (so ``--help``
answers at once), and the library modules that implement each name take their list from
here, so a name exists in one place. ``tests/test_names.py`` checks that every name listed
here is implemented where it is used.
"""

from __future__ import annotations

from pathlib import Path

__all__ = [
    "CAUSAL_METHODS",
    "MASK_SOURCES",
    "MOTION_KINDS",
    "OFFLINE_METHODS",
    "ONNX_SMOOTHERS",
    "OUTFITS",
    "POSE_PRESETS",
    "SEQUENCE_SMOOTHING",
    "STREAMING_SMOOTHING",
    "VIDEO_SMOOTHING",
    "envmap_dir",
    "light_presets",
]

#: Offline smoothers of a whole light sequence (:func:`relightnet.temporal.smoothing_matrix`).
OFFLINE_METHODS = ("hermite", "poly", "savgol")
#: Causal (streaming) light filters (:mod:`relightnet.temporal.causal`).
CAUSAL_METHODS = ("ema", "one-euro", "fir")
#: Light smoothing of the offline video jobs (avatar, compare, evaluate --light): ``auto``
#: (``pooled`` when the network solves its light, else ``hermite``), ``pooled`` (one light
#: solve per shot from the pooled evidence), an offline or a causal method, or ``none``
#: (:mod:`relightnet.temporal.registry` holds what each name is).
VIDEO_SMOOTHING = ("auto", "pooled", *OFFLINE_METHODS, *CAUSAL_METHODS, "gated-one-euro", "none")
#: Streaming smoothers that can live inside an exported ONNX graph (``onnx-run``'s state).
ONNX_SMOOTHERS = ("none", *CAUSAL_METHODS, "gated-one-euro", "pooled")
#: Light smoothing of the streaming jobs (relight-video, export): ``auto`` (``pooled`` with the
#: light solve's evidence, else ``ema``) or an ONNX smoother.
STREAMING_SMOOTHING = ("auto", *ONNX_SMOOTHERS)
#: Light smoothing of a recorded light file (smooth-light): every method that needs no evidence.
SEQUENCE_SMOOTHING = tuple(n for n in VIDEO_SMOOTHING if n not in ("auto", "pooled"))

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
