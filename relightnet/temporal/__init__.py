"""Light smoothing over time: offline regression (polynomial, Hermite spline, Savitzky–Golay)
with outlier correction and switch splitting, causal filters for streaming/ONNX (EMA,
one-euro, FIR, outlier gate), shot pooling of the light solve, switches seen in the frames'
colour, the irradiance light distance, and quality metrics. :mod:`relightnet.temporal.registry`
implements the methods of the one torch-free table, :data:`relightnet.names.SMOOTHING_METHODS`
(what ``--smoothing`` accepts).
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
from .metrics import jitter, light_drift, light_error, outlier_scores, step_lag
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
    CHANGE_EXPLAINED,
    POOL_SECONDS,
    SWITCH_NOISE,
    PooledSolve,
    changing_segments,
    pool_shot_lights,
    pool_window,
    pooled_step,
    pooled_sums,
    pooling_weights,
)
from .registry import (
    MIN_FIT_FRAMES,
    VideoSmoothing,
    check_smoothing,
    make_smoother,
    resolve_smoothing,
    smooth_sequence,
    smooth_video_lights,
)
from .smoothers import hermite_basis, hermite_matrix, poly_matrix, savgol_matrix, smoothing_matrix
from .switches import COLOUR_STEP, colour_switches, frame_colour, merge_switches

__all__ = [
    "EMAFilter", "FIRFilter", "OneEuroFilter", "OutlierGate", "ema_matrix", "ema_sequence", "ema_step", "fir_sequence",
    "fir_step", "fir_taps", "gate_step", "one_euro_step", "run_causal",
    "light_distance", "light_norm", "light_weights", "local_outlier_threshold", "outlier_threshold",
    "parse_eps", "robust_scale",
    "jitter", "light_drift", "light_error", "outlier_scores", "step_lag",
    "SmoothResult", "detect_switches", "frame_noise", "hermite_basis", "hermite_matrix", "poly_matrix",
    "running_median", "savgol_matrix", "smooth_hermite", "smooth_lights", "smooth_poly", "smooth_savgol",
    "smoothing_matrix",
    "MIN_FIT_FRAMES", "VideoSmoothing", "check_smoothing", "make_smoother", "resolve_smoothing", "smooth_sequence",
    "smooth_video_lights",
    "CHANGE_EXPLAINED", "POOL_SECONDS", "SWITCH_NOISE", "PooledSolve", "changing_segments", "pool_shot_lights",
    "pool_window", "pooled_step", "pooled_sums", "pooling_weights",
    "COLOUR_STEP", "colour_switches", "frame_colour", "merge_switches",
]
