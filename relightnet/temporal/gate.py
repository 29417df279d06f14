"""The causal outlier gate: outlier rejection and switch detection in front of a causal filter.

One step with explicit state, loop-free like the filters of :mod:`relightnet.temporal.causal`
(it exports to ONNX); :class:`~relightnet.temporal.pooling.PooledSolve` uses :func:`gate_step` too.
"""

from __future__ import annotations

import torch

from ..checks import InputError
from .causal import CausalFilter, check_alpha, check_filter_input, check_positive, filter_weights, reset_mask
from .distance import light_distance, light_norm

__all__ = ["gate_step", "OutlierGate"]


def gate_step(
    x: torch.Tensor, gate: torch.Tensor, is_first: torch.Tensor | None,
    eps: float = 3.0, persist: int = 2, gamma: float = 0.05, init: float = 0.05,
    weights: torch.Tensor | None = None,
):
    """Causal outlier test of one frame against the previous output.

    Args:
        x: (B, K, 3) light of this frame.
        gate: (B, 3, K, 3) gate state: [previous output, running innovation scale
            (a constant slot), count of consecutive large innovations (constant slot)].
        is_first: (B,) or (B, 1) restart flags, or None.
        eps: a frame is large when its light distance to the previous output,
            divided by that output's norm, exceeds ``eps`` × the running scale.
        persist: this many consecutive large frames make a switch: accepted, and
            the filter restarts from the frame (persist − 1 frames of lag).
        gamma: update rate of the scale, a running mean of the innovation
            distance clipped at the threshold (so it recovers if set too low).
        init: initial scale (a relative innovation, e.g. 0.05 = 5 % of the light's norm).
        weights: (K,) light-distance weights, optional.

    Returns:
        ``(x_in (B, K, 3), first (B,), switch (B,), outlier (B,), scale (B,), count (B,))``:
        the frame to feed the filter (the previous output for an outlier); the
        filter must restart on ``first | switch``.
    """
    first = reset_mask(is_first, x).reshape(-1)
    pred, scale, count = gate[:, 0], gate[:, 1, 0, 0], gate[:, 2, 0, 0]
    scale = torch.where(first, torch.full_like(scale, init), scale)
    # Innovation relative to the light's norm: a brighter light's larger errors are not outliers.
    d = light_distance(x, pred, weights=weights) / (light_norm(pred, weights) + 1e-12)
    thr = eps * scale
    big = (d > thr) & ~first
    count = torch.where(big, count + 1, torch.zeros_like(count))
    switch = count >= persist
    outlier = big & ~switch
    count = torch.where(switch, torch.zeros_like(count), count)
    new_scale = torch.where(first, scale, (1 - gamma) * scale + gamma * torch.minimum(d, thr))
    x_in = torch.where(outlier[:, None, None], pred, x)
    return x_in, first, switch, outlier, new_scale, count


class OutlierGate(CausalFilter):
    """Causal outlier rejection and switch detection around a causal filter.

    ``forward(x (B, K, 3), state (B, S+4, K, 3), is_first (B,)) -> (y, state)``
    where S is the wrapped filter's state size. A frame far from the previous
    output (see :func:`gate_step`) is replaced by that output; a jump that lasts
    ``persist`` frames is a switch and restarts the filter there. The last state
    slot holds this frame's status (``state[:, -1, 0, 0]``): 0 normal, 1 outlier
    (replaced), 2 switch (the filter restarted). ``lmax``: SH order of the lights.
    """

    def __init__(self, filt: CausalFilter, eps: float = 3.0, persist: int = 2, gamma: float = 0.05,
                 init: float = 0.05, lmax: int = 2) -> None:
        super().__init__()
        self.register_buffer("weights", filter_weights(lmax), persistent=False)
        self.filter = filt
        self.eps = check_positive(eps, "eps")
        if isinstance(persist, bool) or int(persist) != persist or persist < 1:
            raise InputError(f"persist: expected a positive integer, got {persist!r}")
        self.persist = int(persist)
        self.gamma = check_alpha(gamma)
        self.init = check_positive(init, "init")
        self.state_size = filt.state_size + 4

    def forward(self, x, state=None, is_first=None):
        state, is_first = self._prepare(x, state, is_first)
        check_filter_input(x, self.weights)
        s = self.filter.state_size
        x_in, first, switch, outlier, scale, count = gate_step(
            x, state[:, s:s + 3], is_first, self.eps, self.persist, self.gamma, self.init, self.weights
        )
        y, fstate = self.filter(x_in, state[:, :s], first | switch)
        status = outlier.to(x.dtype) + 2 * (switch & ~first).to(x.dtype)
        ones = torch.ones_like(x)
        gate = torch.stack([y, scale[:, None, None] * ones, count[:, None, None] * ones,
                            status[:, None, None] * ones], 1)
        return y, torch.cat([fstate, gate], 1)
