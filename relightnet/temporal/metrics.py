"""Quality measures of smoothed light sequences: jitter, drift, error to the truth, step lag, outlier scores.

All distances are :func:`~relightnet.temporal.distance.light_distance`, the L2 of
the irradiance difference over the sphere (summed over RGB), unless ``space="coeff"``.
"""

from __future__ import annotations

import math

import torch

from ..checks import InputError, ShapeError, check_shape
from .distance import light_distance, light_norm, light_weights

__all__ = ["jitter", "light_drift", "light_error", "step_lag", "outlier_scores"]


def _check_seq(x: torch.Tensor, name: str) -> None:
    check_shape(x, ["...", "T", "K", 3], name=name)


def jitter(lights: torch.Tensor, space: str = "light", mask: torch.Tensor | None = None) -> torch.Tensor:
    """Mean magnitude of the second difference over time.

    ``J = mean_t ‖x_{t+1} − 2 x_t + x_{t−1}‖`` for t = 1 … T−2: zero for lights
    changing linearly in time, large for frame-to-frame noise.

    Args:
        lights: (..., T, K, 3), T ≥ 3.
        space: ``"light"`` (the irradiance light distance; default) or
            ``"coeff"`` (mean absolute value over the K×3 coefficients).
        mask: optional (T,) bool; only centre frames t with ``mask[t]`` count
            (e.g. to leave out the frames around a known light switch).

    Returns:
        (...) jitter.
    """
    _check_seq(lights, "lights")
    n = lights.shape[-3]
    if n < 3:
        raise ShapeError(f"lights: jitter needs at least 3 frames, got {n}")
    d2 = lights[..., 2:, :, :] - 2 * lights[..., 1:-1, :, :] + lights[..., :-2, :, :]
    if space == "light":
        per = light_distance(d2)
    elif space == "coeff":
        per = d2.abs().mean((-2, -1))
    else:
        raise InputError(f"space: expected 'light' or 'coeff', got {space!r}")
    if mask is None:
        return per.mean(-1)
    m = torch.as_tensor(mask, dtype=torch.bool, device=per.device)
    if m.shape != (n,):
        raise ShapeError(f"mask: expected ({n},), got {tuple(m.shape)}")
    m = m[1:-1]
    if not bool(m.any()):
        raise InputError("mask: selects no centre frame")
    return (per * m).sum(-1) / m.sum()


def light_drift(lights: torch.Tensor) -> torch.Tensor:
    """How far each frame's light is from the sequence's mean, over the mean's level: a constant light's
    estimate should not move ((T, K, 3) → (T,) ‖E_t − Ē‖ / ‖Ē‖, irradiance over the sphere)."""
    check_shape(lights, ["T", "K", 3], name="lights")
    mean = lights.mean(0, keepdim=True)
    return light_distance(lights, mean) / light_norm(mean).clamp_min(1e-12)


def light_error(est: torch.Tensor, truth: torch.Tensor, relative: bool = False) -> torch.Tensor:
    """Mean over frames of the light distance to the truth.

    Args:
        est, truth: (..., T, K, 3).
        relative: divide by the mean light norm of the truth.

    Returns:
        (...) error.
    """
    _check_seq(est, "est")
    dims = check_shape(truth, ["...", "T", "K", 3], name="truth")
    check_shape(est, ["...", "T", "K", 3], name="est", dims=dims)
    err = light_distance(est, truth).mean(-1)
    if relative:
        err = err / light_distance(truth).mean(-1).clamp_min(torch.finfo(truth.dtype).tiny)
    return err


def step_lag(est: torch.Tensor, truth: torch.Tensor, step: int, level: float = 0.9) -> torch.Tensor:
    """Frames after a step until the estimate has covered ``level`` of it.

    The step is the truth's jump ``Δ = truth[step] − truth[step−1]``. At frame t
    the progress is ``1 − ⟨truth_t − est_t, Δ⟩ / ⟨Δ, Δ⟩`` in the irradiance
    metric: 0 while the estimate still holds the old light, 1 once it has
    caught up. The lag is the first n ≥ 0 with progress ≥ ``level`` at frame
    ``step + n`` (0 if it is already there on the step frame, e.g. an offline
    smoother that anticipates; ``inf`` if never).

    Args:
        est, truth: (..., T, K, 3).
        step: index of the first frame after the jump, 1 ≤ step < T.
        level: fraction of the step, in (0, 1].

    Returns:
        (...) float lag in frames.
    """
    dims = check_shape(truth, ["...", "T", "K", 3], name="truth")
    check_shape(est, ["...", "T", "K", 3], name="est", dims=dims)
    n = truth.shape[-3]
    if not 1 <= step < n:
        raise InputError(f"step: expected a frame in [1, {n}), got {step}")
    if not 0 < level <= 1:
        raise InputError(f"level: expected a number in (0, 1], got {level}")
    w = light_weights(truth.shape[-2], truth.dtype, truth.device)[:, None]
    delta = truth[..., step, :, :] - truth[..., step - 1, :, :]
    dd = (delta * delta * w).sum((-2, -1))
    if bool((dd <= 0).any()):
        raise InputError(f"truth: no jump at frame {step}")
    err = truth[..., step:, :, :] - est[..., step:, :, :]
    progress = 1 - (err * delta[..., None, :, :] * w).sum((-2, -1)) / dd[..., None]
    reached = progress >= level
    idx = torch.arange(reached.shape[-1], device=truth.device, dtype=truth.dtype)
    big = torch.full_like(idx, math.inf)
    return torch.where(reached, idx, big).amin(-1)


def outlier_scores(pred: torch.Tensor, true: torch.Tensor) -> tuple[float, float]:
    """Recall and precision of outlier flags.

    Args:
        pred, true: (..., T) bool flags (all entries pooled).

    Returns:
        ``(recall, precision)``; recall is 1 when there is no true outlier,
        precision is 1 when nothing is flagged (no false positive).
    """
    pred = torch.as_tensor(pred, dtype=torch.bool)
    true = torch.as_tensor(true, dtype=torch.bool)
    if pred.shape != true.shape:
        raise ShapeError(f"pred: expected the shape of true {tuple(true.shape)}, got {tuple(pred.shape)}")
    tp = int((pred & true).sum())
    n_true, n_pred = int(true.sum()), int(pred.sum())
    return (tp / n_true if n_true else 1.0), (tp / n_pred if n_pred else 1.0)
