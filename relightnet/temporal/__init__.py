"""Light smoothing over time: offline regression (polynomial, Hermite spline, Savitzky–Golay)
with outlier correction and switch splitting, causal filters for streaming/ONNX (EMA,
one-euro, FIR, outlier gate), shot pooling of the light solve, switches seen in the frames'
colour, the irradiance light distance, and quality metrics. :mod:`relightnet.temporal.registry`
implements the methods of the one torch-free table, :data:`relightnet.names.SMOOTHING_METHODS`
(what ``--smoothing`` accepts).

The public names are what smooths a video's lights: by method name (:func:`smooth_video_lights`,
:func:`smooth_sequence`, :func:`make_smoother`), offline (:func:`smooth_lights` → :class:`SmoothResult`,
:func:`smoothing_matrix`, :func:`detect_switches`), causal (:class:`EMAFilter`, :class:`OneEuroFilter`,
:class:`FIRFilter`, :class:`OutlierGate`, :func:`run_causal`), pooled (:func:`pool_shot_lights`,
:class:`PooledSolve`), the switches in the frames' colour, and the metrics. The per-step functions,
the smoothers' matrices and the robust statistics stay in their modules.
"""

from .causal import EMAFilter, FIRFilter, OneEuroFilter, run_causal
from .distance import light_distance
from .gate import OutlierGate
from .metrics import jitter, light_drift, light_error, step_lag
from .offline import SmoothResult, detect_switches, smooth_lights
from .pooling import PooledSolve, changing_segments, pool_shot_lights
from .registry import VideoSmoothing, make_smoother, smooth_sequence, smooth_video_lights
from .smoothers import smoothing_matrix
from .switches import colour_switches, frame_colour

__all__ = [
    "smooth_lights", "SmoothResult", "smooth_sequence", "make_smoother", "smooth_video_lights", "VideoSmoothing",
    "smoothing_matrix", "EMAFilter", "OneEuroFilter", "FIRFilter", "OutlierGate", "run_causal", "pool_shot_lights",
    "PooledSolve", "changing_segments", "colour_switches", "frame_colour", "detect_switches", "light_error", "jitter",
    "light_drift", "step_lag", "light_distance",
]
