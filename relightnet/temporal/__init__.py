"""Light smoothing over time: offline regression (polynomial, Hermite spline, Savitzky–Golay)
with outlier correction and switch splitting, causal filters for streaming/ONNX (EMA,
one-euro, FIR), the irradiance light distance, and quality metrics.
"""

from .causal import (
    EMAFilter,
    FIRFilter,
    OneEuroFilter,
    OutlierGate,
    ema_matrix,
    ema_sequence,
    ema_step,
    fir_sequence,
    fir_step,
    fir_taps,
    gate_step,
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
from .metrics import jitter, light_error, outlier_scores, step_lag
from .offline import (
    SmoothResult,
    detect_switches,
    running_median,
    smooth_hermite,
    smooth_lights,
    smooth_poly,
    smooth_savgol,
)
from .pooling import POOL_SECONDS, PooledSolve, pool_shot_lights, pool_window, pooled_step, pooling_weights
from .smoothers import METHODS, hermite_basis, hermite_matrix, poly_matrix, savgol_matrix, smoothing_matrix

__all__ = [
    "EMAFilter", "FIRFilter", "OneEuroFilter", "OutlierGate", "ema_matrix", "ema_sequence", "ema_step", "fir_sequence",
    "fir_step", "fir_taps", "gate_step", "one_euro_step", "run_causal",
    "light_distance", "light_norm", "light_weights", "local_outlier_threshold", "outlier_threshold",
    "parse_eps", "robust_scale",
    "jitter", "light_error", "outlier_scores", "step_lag",
    "METHODS", "SmoothResult", "detect_switches", "hermite_basis", "hermite_matrix", "poly_matrix",
    "running_median", "savgol_matrix", "smooth_hermite", "smooth_lights", "smooth_poly", "smooth_savgol",
    "smoothing_matrix",
    "POOL_SECONDS", "PooledSolve", "pool_shot_lights", "pool_window", "pooled_step", "pooling_weights",
]
