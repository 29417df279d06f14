"""Light smoothing over time: offline regression (polynomial, Hermite spline, Savitzky–Golay)
with outlier correction and switch splitting, causal filters for streaming/ONNX (EMA,
one-euro, FIR, outlier gate), shot pooling of the light solve, the irradiance light distance,
and quality metrics. :mod:`relightnet.temporal.registry` names every method once (what the
commands' ``--smoothing`` accepts) and builds them.
"""

from .causal import (
    EMAFilter,
    FIRFilter,
    OneEuroFilter,
    ema_matrix,
    ema_sequence,
    ema_step,
    fir_sequence,
    fir_step,
    fir_taps,
    one_euro_step,
    run_causal,
)
from .distance import (
    light_distance,
    light_norm,
    light_weights,
    local_outlier_threshold,
    outlier_threshold,
    parse_eps,
    robust_scale,
)
from .gate import OutlierGate, gate_step
from .metrics import jitter, light_error, outlier_scores, step_lag
from .offline import (
    SmoothResult,
    detect_switches,
    frame_noise,
    running_median,
    smooth_hermite,
    smooth_lights,
    smooth_poly,
    smooth_savgol,
)
from .pooling import (
    POOL_SECONDS,
    SWITCH_NOISE,
    PooledSolve,
    pool_shot_lights,
    pool_window,
    pooled_step,
    pooling_weights,
)
from .registry import (
    SEQUENCE_SMOOTHING,
    SMOOTHING_METHODS,
    STREAMING_SMOOTHING,
    VIDEO_SMOOTHING,
    SmoothingMethod,
    check_smoothing,
    make_smoother,
    resolve_smoothing,
    smooth_sequence,
    smoothing_names,
)
from .smoothers import METHODS, hermite_basis, hermite_matrix, poly_matrix, savgol_matrix, smoothing_matrix

__all__ = [
    "EMAFilter", "FIRFilter", "OneEuroFilter", "OutlierGate", "ema_matrix", "ema_sequence", "ema_step", "fir_sequence",
    "fir_step", "fir_taps", "gate_step", "one_euro_step", "run_causal",
    "light_distance", "light_norm", "light_weights", "local_outlier_threshold", "outlier_threshold",
    "parse_eps", "robust_scale",
    "jitter", "light_error", "outlier_scores", "step_lag",
    "METHODS", "SmoothResult", "detect_switches", "frame_noise", "hermite_basis", "hermite_matrix", "poly_matrix",
    "running_median", "savgol_matrix", "smooth_hermite", "smooth_lights", "smooth_poly", "smooth_savgol",
    "smoothing_matrix",
    "SEQUENCE_SMOOTHING", "SMOOTHING_METHODS", "STREAMING_SMOOTHING", "VIDEO_SMOOTHING", "SmoothingMethod",
    "check_smoothing", "make_smoother", "resolve_smoothing", "smooth_sequence", "smoothing_names",
    "POOL_SECONDS", "SWITCH_NOISE", "PooledSolve", "pool_shot_lights", "pool_window", "pooled_step", "pooling_weights",
]
