"""Offline smoothing of a whole light sequence: polynomial, Hermite spline, Savitzky–Golay, outliers, switches.

The methods (``"hermite"``, ``"poly"``, ``"savgol"``) are linear smoothers built
by :mod:`relightnet.temporal.smoothers`: ``smoothed = S @ x`` with a (T, T) matrix S
that does not depend on the data, so one matmul smooths all K×3 coefficients of
all frames and the result is differentiable in the lights.

Outliers (:func:`smooth_lights` with ``outlier_eps``): a frame whose
:func:`~relightnet.temporal.distance.light_distance` from the current fit exceeds
the threshold (per frame, from the distances of the frames around it within its
segment) is replaced by the fit, and the sequence is refit — solved directly
for the fixed point of that replace-and-refit loop, ``(I − S D) y = S (I − D) x``
with D the outlier indicator, one (T, T) solve per sequence. The first reference
is a 5-frame running median (robust to isolated spikes). Flags are recomputed
from the raw frames at every pass (``iterations``), so a frame flagged only
because a spike pulled the early fit is released later; at most about half the
frames of any window are flagged.

Switches (``switches="auto"``, :func:`detect_switches`): a jump that persists — the
light changes and stays changed — is a switch, not an outlier. The sequence is
split there and each segment is smoothed on its own, so the output follows the
step at once instead of blurring it over a knot interval.

Example:
    Noisy frames of one steady light come out near it; one wild frame is flagged and replaced:

    >>> import torch
    >>> from relightnet.temporal import smooth_lights
    >>> g = torch.Generator().manual_seed(0)
    >>> light = torch.randn(9, 3, generator=g)
    >>> raw = light + 0.01 * torch.randn(60, 9, 3, generator=g)
    >>> raw[30] += 5.0
    >>> res = smooth_lights(raw, "hermite", outlier_eps="8mad")
    >>> res.smoothed.shape, res.outliers.nonzero().flatten().tolist()
    (torch.Size([60, 9, 3]), [30])
    >>> bool((res.smoothed - light).abs().max() < 0.05)
    True
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F

from ..checks import InputError, ShapeError, check_finite, check_sh_count
from .distance import light_distance, light_norm, local_outlier_threshold, outlier_threshold, parse_eps
from .smoothers import _check_method, _check_pos, smoothing_matrix

__all__ = [
    "SmoothResult", "running_median", "frame_noise", "detect_switches",
    "smooth_lights", "smooth_poly", "smooth_savgol", "smooth_hermite",
]


@dataclass(frozen=True)
class SmoothResult:
    """What :func:`smooth_lights` returns. Leading ``B`` only for batched input.

    Attributes:
        smoothed: (B, T, K, 3) smoothed (and outlier-corrected) lights.
        outliers: (B, T) bool, frames flagged as outliers in the last pass.
        distances: (B, T) light distance from each raw frame to the smoothed one.
        switches: (B, T) bool, True on the first frame of each new segment.
    """

    smoothed: torch.Tensor
    outliers: torch.Tensor
    distances: torch.Tensor
    switches: torch.Tensor


# ----------------------------------------------------------------------------- robust helpers


def running_median(x: torch.Tensor, window: int = 5) -> torch.Tensor:
    """Per-coefficient running median over frames, window shifted inward at the ends.

    Args:
        x: (B, T, N) sequences.
        window: odd window (reduced to fit T).

    Returns:
        (B, T, N); steps are kept, runs of < window/2 outlying frames are removed.
    """
    t_len = x.shape[1]
    w = min(window, t_len)
    w -= 1 - w % 2
    t = torch.arange(t_len, device=x.device)
    idx = (t - w // 2).clamp(0, t_len - w)[:, None] + torch.arange(w, device=x.device)  # (T, w)
    return x[:, idx].median(dim=2).values


def _as_batch(lights: torch.Tensor, name: str = "lights") -> tuple[torch.Tensor, bool]:
    if not isinstance(lights, torch.Tensor):
        raise InputError(f"{name}: expected a torch.Tensor, got {type(lights).__name__}")
    if lights.dim() not in (3, 4) or lights.shape[-1] != 3:
        raise ShapeError(f"{name}: expected (T, K, 3) or (B, T, K, 3), got {tuple(lights.shape)}")
    check_sh_count(lights, name)
    if not lights.is_floating_point():
        raise InputError(f"{name}: expected floating-point coefficients, got {lights.dtype}")
    if lights.shape[-3] < 1:
        raise ShapeError(f"{name}: expected at least one frame, got {tuple(lights.shape)}")
    check_finite(lights, name)
    return (lights if lights.dim() == 4 else lights[None]), lights.dim() == 4


def detect_switches(
    lights: torch.Tensor, window: int = 5, eps="8mad", min_jump: float = 0.0, noise: float | None = None
) -> torch.Tensor:
    """Find persistent jumps (light switches) in light sequences.

    The sequence is cleaned by a 5-frame running median (isolated outliers go,
    steps stay); the jump at frame t is the light distance between the means of
    the ``window`` cleaned frames before and after t. It peaks at a step;
    a peak above the threshold (``eps`` over the sequence's jump values, at
    least ``min_jump``, and with ``noise`` at least that many times the
    sequence's :func:`frame_noise`) that is the largest within ``window``
    frames is a switch.

    Args:
        lights: (T, K, 3) or (B, T, K, 3).
        window: frames on each side; a switch is never within ``window`` frames
            of the sequence's ends, and switches are more than ``window`` apart.
        eps: threshold as for :func:`~relightnet.temporal.distance.parse_eps`
            (None only with ``noise``).
        min_jump: absolute lower bound of the threshold (light distance).
        noise: lower bound of the threshold in units of the frame noise. A
            threshold over the jump values needs many frames away from any step;
            one over the frame noise also works on a clip that is mostly
            step (a short shot, or a switch half-way). With it, a peak must
            also be twice the jumps ``window`` frames to either side, so that a
            light turning steadily (a flat jump profile) is no switch.

    Returns:
        (T,) or (B, T) bool, True on the first frame after each switch.
    """
    x, batched = _as_batch(lights)
    window = _check_pos(window, "window")
    by_jumps = parse_eps(eps) is not None
    if not by_jumps and noise is None:
        raise InputError("switch eps: expected a threshold, got none")
    if noise is not None and not noise > 0:
        raise InputError(f"switch noise: expected a positive number, got {noise!r}")
    b, t_len, k, _ = x.shape
    out = torch.zeros(b, t_len, dtype=torch.bool, device=x.device)
    if t_len >= 2 * window + 1:
        c = running_median(x.reshape(b, t_len, k * 3), 5).reshape(b, t_len, k, 3)
        csum = F.pad(c.cumsum(1), (0, 0, 0, 0, 1, 0))  # csum[j] = sum of frames < j
        t = torch.arange(window, t_len - window + 1, device=x.device)
        left = (csum[:, t] - csum[:, t - window]) / window
        right = (csum[:, t + window] - csum[:, t]) / window
        jump = light_distance(left, right)  # (B, len(t)), jump at boundary t (between t-1 and t)
        floor = torch.full((b,), float(min_jump), dtype=x.dtype, device=x.device)
        if noise is not None:
            floor = torch.maximum(floor, noise * frame_noise(x))
        thr = outlier_threshold(jump, eps, floor=floor) if by_jumps else floor
        peak = F.max_pool1d(jump[:, None], 2 * window + 1, 1, window)[:, 0]
        first = torch.ones_like(jump, dtype=torch.bool)
        first[:, 1:] = jump[:, 1:] > jump[:, :-1]  # on a flat top keep only the first frame
        hit = (jump > thr[:, None]) & (jump >= peak) & first
        if noise is not None:  # a step's jump profile peaks; a steady ramp's (a light turning) is flat
            pad = F.pad(jump[:, None], (window, window), mode="replicate")[:, 0]
            hit &= jump > 2 * torch.maximum(pad[:, :-2 * window], pad[:, 2 * window:])
        for bi, ti in hit.nonzero().tolist():
            out[bi, _refine_switch(x[bi], int(t[ti]), window)] = True
    return out if batched else out[0]


def frame_noise(lights: torch.Tensor) -> torch.Tensor:
    """How much single frames scatter: the median light distance of a frame from the 5-frame
    running median of its sequence ((T, K, 3) → (), (B, T, K, 3) → (B,)). A step moves few
    frames away from the running median, noise moves all of them."""
    x, batched = _as_batch(lights)
    b, t_len, k, _ = x.shape
    med = running_median(x.reshape(b, t_len, k * 3), 5).reshape(b, t_len, k, 3)
    out = light_distance(x, med).median(-1).values
    return out if batched else out[0]


def _refine_switch(x: torch.Tensor, t: int, window: int) -> int:
    """Exact frame of a switch found near t: the split of frames [t−h, t+h) that best separates the two lights.

    Each side's light is the median of the frames 2 or more away from t; each frame
    costs its light distance to its side's light (L1: an outlier costs about the same
    on either side, so it cannot pull the split).
    """
    h = window
    r = min(2, h - 1)
    left = x[t - h:t - r].median(dim=0).values
    right = x[t + r:t + h].median(dim=0).values
    seg = x[t - h:t + h]
    d_left, d_right = light_distance(seg, left), light_distance(seg, right)
    # cost(s) = Σ_{j<s} d_left + Σ_{j≥s} d_right for splits s = t−r … t+r.
    cl = F.pad(d_left.cumsum(0), (1, 0))
    cr = F.pad(d_right.flip(0).cumsum(0), (1, 0)).flip(0)
    splits = torch.arange(h - r, h + r + 1)
    cost = cl[splits] + cr[splits]
    return t - h + int(splits[int(cost.argmin())])


# ----------------------------------------------------------------------------- smoothing


def _corrected_fit(S, x, out, ref, eye, ridge: float = 1e-4):
    """Fixed point of "replace the outliers by the fit, refit": ``y = S (W x + D y)``.

    With D = diag(outliers), W = I − D this is ``(I − S D) y = S W x``, one linear
    solve per sequence. A small ridge on the outlier frames pulls directions that
    only outlier frames determine (e.g. a knot whose whole support is flagged)
    toward the reference ``ref`` instead of leaving them undetermined.

    Args:
        S: (B, T, T); x, ref: (B, T, N); out: (B, T) 0/1; eye: (T, T).
    """
    A = eye - S * out[:, None, :] + ridge * torch.diag_embed(out)
    rhs = S @ (x * (1 - out)[..., None]) + ridge * out[..., None] * ref
    return torch.linalg.solve(A, rhs)


def smooth_lights(
    lights: torch.Tensor,
    method: str = "hermite",
    *,
    outlier_eps=None,
    iterations: int = 3,
    switches=None,
    switch_window: int = 5,
    switch_eps="8mad",
    scale_window: int | None = 61,
    **opts,
) -> SmoothResult:
    """Smooth light sequences over time, with optional outlier correction and switch splitting.

    Args:
        lights: (T, K, 3) or (B, T, K, 3) per-frame lights.
        method: ``"hermite"`` (default), ``"poly"`` or ``"savgol"``.
        outlier_eps: None (no outliers), an absolute light distance, or ``"<c>mad"``.
        iterations: outlier passes when ``outlier_eps`` is set: flag the frames far
            from the current fit, then solve for the fit with those frames replaced.
        switches: None (one segment), ``"auto"`` (:func:`detect_switches`), or
            (T,)/(B, T) bool marking segment starts.
        switch_window, switch_eps: options of :func:`detect_switches`.
        scale_window: frames over which the ``"<c>mad"`` statistics are taken
            around each frame (None: the whole segment); see
            :func:`~relightnet.temporal.distance.local_outlier_threshold`.
        **opts: the method's options, see :func:`smoothing_matrix`.

    Returns:
        :class:`SmoothResult` with the leading B only for batched input.
    """
    _check_method(method)
    x, batched = _as_batch(lights)
    iterations = _check_pos(iterations, "iterations")
    if scale_window is not None:
        scale_window = _check_pos(scale_window, "scale_window")
    b, t_len, k, _ = x.shape
    if switches is None or switches is False:
        sw = torch.zeros(b, t_len, dtype=torch.bool, device=x.device)
    elif isinstance(switches, str):
        if switches != "auto":
            raise InputError(f"switches: expected None, 'auto' or a bool mask, got {switches!r}")
        sw = detect_switches(x, switch_window, switch_eps)
    else:
        sw = torch.as_tensor(switches, dtype=torch.bool, device=x.device)
        if sw.shape not in ((t_len,), (b, t_len)):
            raise ShapeError(f"switches: expected ({t_len},) or ({b}, {t_len}), got {tuple(sw.shape)}")
        sw = sw.expand(b, t_len)
    cache: dict[bytes, torch.Tensor] = {}
    mats = []
    for row in sw.cpu():
        key = row.numpy().tobytes()
        if key not in cache:
            cache[key] = smoothing_matrix(t_len, method, row, **opts).to(x.dtype).to(x.device)
        mats.append(cache[key])
    S = torch.stack(mats)  # (B, T, T)
    flat = x.reshape(b, t_len, k * 3)
    outliers = torch.zeros(b, t_len, dtype=torch.bool, device=x.device)
    if parse_eps(outlier_eps) is None:
        fit = S @ flat
    else:
        fit = running_median(flat, 5)
        # Floor: far below any real deviation, above the rounding error of an exact fit.
        floor = 1e-5 * light_norm(fit.reshape(x.shape)) + torch.finfo(x.dtype).tiny
        eye = torch.eye(t_len, dtype=x.dtype, device=x.device)
        for _ in range(iterations):
            d = light_distance(x, fit.reshape(x.shape))
            thr = torch.empty_like(d)
            for i in range(b):  # thresholds never mix segments (a switch may change the noise level)
                bounds = [0, *sw[i].nonzero().flatten().tolist(), t_len]
                for a, e in zip(bounds[:-1], bounds[1:], strict=False):
                    thr[i, a:e] = local_outlier_threshold(d[i, a:e], outlier_eps, scale_window, floor[i, a:e])
            outliers = d > thr
            fit = _corrected_fit(S, flat, outliers.to(x.dtype), fit, eye)
    smoothed = fit.reshape(x.shape)
    res = SmoothResult(smoothed, outliers, light_distance(x, smoothed), sw)
    if batched:
        return res
    return SmoothResult(res.smoothed[0], res.outliers[0], res.distances[0], res.switches[0])


def smooth_poly(lights: torch.Tensor, degree: int = 2, window: int | None = None, **kw) -> SmoothResult:
    """:func:`smooth_lights` with ``method="poly"``: (T, K, 3) or (B, T, K, 3) lights."""
    return smooth_lights(lights, "poly", degree=degree, window=window, **kw)


def smooth_savgol(lights: torch.Tensor, window: int = 9, degree: int = 2, **kw) -> SmoothResult:
    """:func:`smooth_lights` with ``method="savgol"``: (T, K, 3) or (B, T, K, 3) lights."""
    return smooth_lights(lights, "savgol", window=window, degree=degree, **kw)


def smooth_hermite(
    lights: torch.Tensor, knot_spacing: float = 8, tangents: str = "catmull-rom", **kw
) -> SmoothResult:
    """:func:`smooth_lights` with ``method="hermite"``: (T, K, 3) or (B, T, K, 3) lights."""
    return smooth_lights(lights, "hermite", knot_spacing=knot_spacing, tangents=tangents, **kw)
