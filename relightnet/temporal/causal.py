"""Causal (streaming) light filters whose state is an explicit input and output.

Each filter is one step, ``forward(x_t, state, is_first) -> (y_t, new_state)``,
made of tensor ops only: no loop over frames, no data-dependent Python control
flow, so it exports to ONNX inside a per-frame network. A video is filtered by
feeding ``new_state`` back as ``state``; ``is_first`` (B,) or (B, 1), bool or
0/1, restarts a sequence (the state is replaced by the current frame through
``torch.where``), which is how an exported graph starts a new video. The state
is one tensor (B, S, K, 3); ``init_state(x)`` gives a zero one and
:func:`run_causal` loops over a whole sequence in Python for offline use.

- :class:`EMAFilter`: ``y_t = α x_t + (1 − α) y_{t−1}``, ``y_0 = x_0``.
  Step response after n frames: ``1 − (1 − α)^{n+1}``.
- :class:`OneEuroFilter` (Casiez, Roussel & Vogel, CHI 2012): an EMA whose cutoff
  rises with the speed of the light, ``f_c = min_cutoff + beta · speed``, so slow
  drifts are smoothed hard and fast changes pass with little lag. The speed is one
  number per light: the light distance (irradiance metric) of the low-passed
  derivative, divided by the light's norm when ``normalize`` (1/s, scale-free).
- :class:`FIRFilter`: ``y_t = Σ_j h_j x_{t−j}`` over the last ``window`` frames;
  :func:`fir_taps` gives a moving average (degree 0) or the causal least-squares
  polynomial evaluated at the newest frame (degree ≥ 1: no lag on ramps).
- :class:`~relightnet.temporal.gate.OutlierGate` (in :mod:`relightnet.temporal.gate`) wraps
  any of them: a frame far from the previous output (relative to a running scale) is replaced
  by it; a jump that persists for ``persist`` frames is a switch and restarts the filter (so
  steps are followed within ``persist − 1`` frames while isolated spikes are dropped).

Loop-free whole-sequence forms for torch use: :func:`ema_sequence` (a
lower-triangular (T, T) matmul, :func:`ema_matrix`) and :func:`fir_sequence`
(``conv1d``); they equal the stepwise filters.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import nn

from ..checks import InputError, ShapeError, check_sh_count, check_shape
from .distance import light_norm, light_weights

__all__ = [
    "ema_step", "one_euro_step", "fir_step", "fir_taps", "ema_matrix", "ema_sequence", "fir_sequence",
    "EMAFilter", "OneEuroFilter", "FIRFilter", "run_causal",
    "CausalFilter", "reset_mask", "check_alpha", "check_positive", "filter_weights", "check_filter_input",
]



def reset_mask(is_first: torch.Tensor | None, x: torch.Tensor) -> torch.Tensor:
    """(B, 1, 1) bool reset mask from (B,) or (B, 1) ``is_first``."""
    if is_first is None:
        return torch.zeros(x.shape[0], 1, 1, dtype=torch.bool, device=x.device)
    f = is_first if is_first.dtype == torch.bool else is_first != 0
    return f.reshape(-1, 1, 1)


def _alpha(cutoff, rate: float):
    """Smoothing factor of a one-pole low-pass at ``cutoff`` Hz sampled at ``rate`` Hz."""
    return 1.0 / (1.0 + rate / (2 * math.pi * cutoff))


def check_alpha(alpha) -> float:
    """``alpha`` as a float when it is a number in (0, 1], else an :class:`InputError`."""
    if not (isinstance(alpha, (int, float)) and 0 < alpha <= 1):
        raise InputError(f"alpha: expected a number in (0, 1], got {alpha!r}")
    return float(alpha)


def check_positive(value, name: str) -> float:
    """``value`` as a float when it is a finite number > 0, else an :class:`InputError` naming ``name``."""
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise InputError(f"{name}: expected a positive number, got {value!r}")
    return float(value)


def filter_weights(lmax: int) -> torch.Tensor:
    """(K,) weights of the light distance for order ``lmax`` (:func:`~relightnet.temporal.distance.light_weights`)."""
    if isinstance(lmax, bool) or int(lmax) != lmax or lmax < 0:
        raise InputError(f"lmax: expected a non-negative integer, got {lmax!r}")
    return light_weights((int(lmax) + 1) ** 2)


def check_filter_input(x: torch.Tensor, weights: torch.Tensor) -> None:
    """Refuse frames ``x`` that are not (B, K, 3) with the K of the filter's (K,) ``weights``."""
    if x.dim() != 3 or x.shape[1] != weights.shape[0] or x.shape[2] != 3:
        raise ShapeError(f"x: expected (B, {weights.shape[0]}, 3) (the filter's lmax), got {tuple(x.shape)}")


# ----------------------------------------------------------------------------- functional steps


def ema_step(x: torch.Tensor, state: torch.Tensor, is_first: torch.Tensor | None, alpha: float):
    """One EMA step.

    Args:
        x: (B, K, 3) light of this frame.
        state: (B, 1, K, 3) previous output.
        is_first: (B,) or (B, 1) restart flags, or None.
        alpha: weight of the new frame, in (0, 1].

    Returns:
        ``(y (B, K, 3), new_state (B, 1, K, 3))``.
    """
    y = torch.where(reset_mask(is_first, x), x, alpha * x + (1 - alpha) * state[:, 0])
    return y, y[:, None]


def one_euro_step(
    x: torch.Tensor,
    state: torch.Tensor,
    is_first: torch.Tensor | None,
    min_cutoff: float = 0.5,
    beta: float = 1.0,
    d_cutoff: float = 1.0,
    rate: float = 30.0,
    normalize: bool = True,
    weights: torch.Tensor | None = None,
):
    """One one-euro step.

    Args:
        x: (B, K, 3) light of this frame.
        state: (B, 2, K, 3): [low-passed derivative (per second), previous output].
        is_first: (B,) or (B, 1) restart flags, or None.
        min_cutoff: cutoff (Hz) at rest. beta: cutoff increase per unit speed.
        d_cutoff: cutoff (Hz) of the derivative's low-pass. rate: frames per second.
        normalize: divide the speed by the light's norm.
        weights: (K,) light-distance weights (:func:`~relightnet.temporal.distance.light_weights`), optional.

    Returns:
        ``(y (B, K, 3), new_state (B, 2, K, 3))``.
    """
    first = reset_mask(is_first, x)
    dx_prev, y_prev = state[:, 0], state[:, 1]
    a_d = _alpha(d_cutoff, rate)
    edx = a_d * (x - y_prev) * rate + (1 - a_d) * dx_prev
    edx = torch.where(first, torch.zeros_like(edx), edx)
    speed = light_norm(edx, weights)  # (B,)
    if normalize:
        speed = speed / (light_norm(x, weights) + 1e-12)
    cutoff = min_cutoff + beta * speed
    a = (1.0 / (1.0 + rate / (2 * math.pi * cutoff)))[:, None, None]
    y = torch.where(first, x, a * x + (1 - a) * y_prev)
    return y, torch.stack([edx, y], 1)


def fir_step(x: torch.Tensor, state: torch.Tensor, is_first: torch.Tensor | None, taps: torch.Tensor):
    """One FIR step.

    Args:
        x: (B, K, 3) light of this frame.
        state: (B, W−1, K, 3) previous W−1 inputs, oldest first.
        is_first: (B,) or (B, 1) restart flags, or None (a restart fills the history with x).
        taps: (W,) weights, ``taps[j]`` multiplies the input j frames ago.

    Returns:
        ``(y (B, K, 3), new_state (B, W−1, K, 3))``.
    """
    hist = torch.where(reset_mask(is_first, x)[:, None], x[:, None].expand_as(state), state)
    win = torch.cat([hist, x[:, None]], 1)  # (B, W, K, 3), newest last
    y = torch.einsum("w,bwkc->bkc", taps.flip(0).to(x.dtype), win)
    return y, win[:, 1:]


def fir_taps(window: int = 5, degree: int = 0, dtype=torch.float32) -> torch.Tensor:
    """Causal FIR taps: least-squares polynomial of ``degree`` over the last ``window`` frames at the newest.

    Degree 0 is the moving average. Taps sum to 1 (constants pass unchanged) and
    polynomials of degree ≤ ``degree`` pass without lag.

    Returns:
        (W,) taps, ``taps[j]`` for the input j frames ago.
    """
    if isinstance(window, bool) or int(window) != window or window < 1:
        raise InputError(f"window: expected a positive integer, got {window!r}")
    if isinstance(degree, bool) or int(degree) != degree or not 0 <= degree < window:
        raise InputError(f"degree: expected an integer in [0, window), got {degree!r}")
    u = -torch.arange(int(window), dtype=torch.float64)
    V = u[:, None] ** torch.arange(int(degree) + 1, dtype=torch.float64)
    return (V @ torch.linalg.pinv(V))[0].to(dtype)


# ----------------------------------------------------------------------------- loop-free sequence forms


def _seq(lights: torch.Tensor) -> tuple[torch.Tensor, bool]:
    check_shape(lights, ["...", "K", 3], name="lights")
    if lights.dim() not in (3, 4):
        raise ShapeError(f"lights: expected (T, K, 3) or (B, T, K, 3), got {tuple(lights.shape)}")
    check_sh_count(lights, "lights")
    return (lights if lights.dim() == 4 else lights[None]), lights.dim() == 4


def ema_matrix(n: int, alpha: float, dtype=torch.float32, device=None) -> torch.Tensor:
    """(T, T) lower-triangular matrix M with ``ema_sequence(x) = M @ x``.

    ``M[t, j] = α (1−α)^{t−j}`` for 1 ≤ j ≤ t and ``M[t, 0] = (1−α)^t`` (y_0 = x_0).

    Example:
        >>> from relightnet.temporal.causal import ema_matrix
        >>> ema_matrix(3, 0.5).tolist()
        [[1.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.25, 0.25, 0.5]]
    """
    alpha = check_alpha(alpha)
    t = torch.arange(n, dtype=torch.float64, device=device)
    lag = t[:, None] - t[None, :]
    M = torch.where(lag >= 0, alpha * (1 - alpha) ** lag.clamp_min(0), torch.zeros((), dtype=torch.float64))
    M[:, 0] = (1 - alpha) ** t
    return M.to(dtype)


def ema_sequence(lights: torch.Tensor, alpha: float) -> torch.Tensor:
    """EMA of whole sequences in one matmul: (T, K, 3) or (B, T, K, 3) → same shape.

    Example:
        A step from light 0 to light 1 is followed at the rate α:

        >>> import torch
        >>> from relightnet.temporal.causal import ema_sequence
        >>> lights = torch.zeros(4, 9, 3)
        >>> lights[1:] = 1.0
        >>> ema_sequence(lights, alpha=0.5)[:, 0, 0].tolist()
        [0.0, 0.5, 0.75, 0.875]
    """
    x, batched = _seq(lights)
    b, n, k, _ = x.shape
    y = (ema_matrix(n, alpha, x.dtype, x.device) @ x.reshape(b, n, k * 3)).reshape(x.shape)
    return y if batched else y[0]


def fir_sequence(lights: torch.Tensor, taps: torch.Tensor) -> torch.Tensor:
    """Causal FIR of whole sequences as ``conv1d`` (first frame repeated before the start).

    Args:
        lights: (T, K, 3) or (B, T, K, 3).
        taps: (W,) as in :func:`fir_step`.

    Returns:
        Same shape as ``lights``.
    """
    x, batched = _seq(lights)
    b, n, k, _ = x.shape
    w = taps.shape[0]
    sig = x.permute(0, 2, 3, 1).reshape(b * k * 3, 1, n)
    sig = torch.cat([sig[..., :1].expand(-1, -1, w - 1), sig], -1)
    y = F.conv1d(sig, taps.flip(0).to(x.dtype).reshape(1, 1, w))
    y = y.reshape(b, k, 3, n).permute(0, 3, 1, 2)
    return y if batched else y[0]


# ----------------------------------------------------------------------------- modules


class CausalFilter(nn.Module):
    """The base of the streaming filters: ``forward(x (B, K, 3), state (B, S, K, 3), is_first (B,))
    -> (y, state)``, with ``state_size`` S and a zero :meth:`init_state`."""

    state_size: int = 1

    def init_state(self, x: torch.Tensor) -> torch.Tensor:
        """Zero state (B, S, K, 3) for frames x (B, K, 3); pair it with ``is_first`` = True."""
        return x.new_zeros(x.shape[0], self.state_size, *x.shape[1:])

    def _prepare(self, x, state, is_first):
        if state is None:
            state = self.init_state(x)
            is_first = torch.ones(x.shape[0], dtype=torch.bool, device=x.device)
        return state, is_first


class EMAFilter(CausalFilter):
    """Exponential moving average; ``forward(x (B, K, 3), state (B, 1, K, 3), is_first (B,)) -> (y, state)``."""

    state_size = 1

    def __init__(self, alpha: float = 0.3) -> None:
        super().__init__()
        self.alpha = check_alpha(alpha)

    def forward(self, x, state=None, is_first=None):
        state, is_first = self._prepare(x, state, is_first)
        return ema_step(x, state, is_first, self.alpha)


class OneEuroFilter(CausalFilter):
    """One-euro filter; ``forward(x (B, K, 3), state (B, 2, K, 3), is_first (B,)) -> (y, state)``.

    Args: see :func:`one_euro_step`; ``lmax`` is the SH order of the lights it will filter.
    """

    state_size = 2

    def __init__(
        self, min_cutoff: float = 0.5, beta: float = 1.0, d_cutoff: float = 1.0, rate: float = 30.0,
        normalize: bool = True, lmax: int = 2,
    ) -> None:
        super().__init__()
        self.register_buffer("weights", filter_weights(lmax), persistent=False)
        self.min_cutoff = check_positive(min_cutoff, "min_cutoff")
        if not (isinstance(beta, (int, float)) and math.isfinite(beta) and beta >= 0):
            raise InputError(f"beta: expected a non-negative number, got {beta!r}")
        self.beta = float(beta)
        self.d_cutoff = check_positive(d_cutoff, "d_cutoff")
        self.rate = check_positive(rate, "rate")
        self.normalize = bool(normalize)

    def forward(self, x, state=None, is_first=None):
        state, is_first = self._prepare(x, state, is_first)
        check_filter_input(x, self.weights)
        return one_euro_step(x, state, is_first, self.min_cutoff, self.beta, self.d_cutoff, self.rate,
                             self.normalize, self.weights)


class FIRFilter(CausalFilter):
    """Causal FIR; ``forward(x (B, K, 3), state (B, W−1, K, 3), is_first (B,)) -> (y, state)``.

    Args:
        window: number of taps W (ignored when ``taps`` is given).
        degree: see :func:`fir_taps`.
        taps: explicit (W,) taps, W ≥ 2.
    """

    def __init__(self, window: int = 5, degree: int = 0, taps: torch.Tensor | None = None) -> None:
        super().__init__()
        taps = fir_taps(window, degree) if taps is None else torch.as_tensor(taps, dtype=torch.float32)
        if taps.dim() != 1 or taps.shape[0] < 2:
            raise ShapeError(f"taps: expected (W,) with W >= 2, got {tuple(taps.shape)}")
        self.register_buffer("taps", taps)
        self.state_size = taps.shape[0] - 1

    def forward(self, x, state=None, is_first=None):
        state, is_first = self._prepare(x, state, is_first)
        return fir_step(x, state, is_first, self.taps)


def run_causal(module: nn.Module, lights: torch.Tensor, return_states: bool = False):
    """Filter whole sequences frame by frame (a Python loop; for offline use and tests).

    Args:
        module: a causal filter of this module.
        lights: (T, K, 3) or (B, T, K, 3).
        return_states: also return the state after every frame.

    Returns:
        Same shape as ``lights``: the filtered lights, the state reset on frame 0;
        with ``return_states``, also the states (T, S, K, 3) or (B, T, S, K, 3).
    """
    x, batched = _seq(lights)
    state = module.init_state(x[:, 0])
    first = torch.ones(x.shape[0], dtype=torch.bool, device=x.device)
    out, states = [], []
    for t in range(x.shape[1]):
        y, state = module(x[:, t], state, first if t == 0 else ~first)
        out.append(y)
        states.append(state)
    y = torch.stack(out, 1)
    if not return_states:
        return y if batched else y[0]
    st = torch.stack(states, 1)
    return (y, st) if batched else (y[0], st[0])
