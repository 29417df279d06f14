"""A video's light estimated as a video: the per-frame evidence of the light solve, pooled over a shot.

A network that solves its light (``light_mode`` ``solve``/``hybrid``,
:mod:`relightnet.sh.light_solve`) gives, with every frame, the normal equations of its
solve (:class:`~relightnet.sh.light_solve.Evidence`). Frames under the same light add
their evidence and share one solve, so a constant light gives a constant estimate however
the person turns, while a light switch splits the shot:

- offline (:func:`pool_shot_lights`): per-frame solves → :func:`~relightnet.temporal.offline.detect_switches`
  → one joint solve per segment (``window=None``: the frames' errors average out over the whole
  segment, so a person turning under a constant light cannot move the light), or per sliding
  window of frames inside the segment (``window`` frames, triangular weights), or — what the
  video jobs use — one solve per segment unless its light changes (:func:`changing_segments`:
  a change that is low-order in time explains most of the frames' scatter), that segment then
  pooled over ``change_window`` frames so that the change is followed;
- causal (:class:`PooledSolve`, one step with explicit state, loop-free, so it lives inside the
  exported ONNX graph): an outlier gate on the per-frame light (:func:`~relightnet.temporal.gate.gate_step`:
  isolated outliers are dropped, a jump that persists ``persist`` frames restarts the pool) and
  a running mean of the evidence since the last restart, with a floor ``alpha`` on the new
  frame's weight so that slow changes are followed (memory about ``1/alpha`` frames).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from ..checks import InputError, check_shape
from ..sh.light_solve import Evidence, solve_light
from .causal import CausalFilter, check_alpha, check_positive, filter_weights
from .distance import light_distance
from .gate import gate_step
from .offline import detect_switches
from .switches import colour_switches, merge_switches

__all__ = ["POOL_SECONDS", "SWITCH_NOISE", "CHANGE_EXPLAINED", "pool_window", "pooling_weights", "pooled_sums",
           "changing_segments", "pool_shot_lights", "pooled_step", "PooledSolve"]

#: How far (seconds) the video jobs pool a frame's evidence to either side in a segment whose light
#: changes (:func:`changing_segments`): a light that turns (a camera pan) is followed. 2 s, not 1 s:
#: on turning clips the estimate's error did not change (the per-frame error dominates); the window's
#: own cost on a light turning up to 60°/s is p90 0.13 vs 0.07 (``benchmarks/bench_pooling.py``).
POOL_SECONDS = 2.0

#: A segment's light changes when a quadratic in time fitted to its per-frame lights leaves at most
#: ``1 − CHANGE_EXPLAINED`` of their scatter about the segment's mean (light distance squared). A
#: network's per-frame errors are themselves slow (they follow the person's turn): on real footage
#: of a person turning under a constant light a quadratic explains 10–20% of the scatter over the
#: whole clip and up to 43% over 2 s; on generated clips under a constant light up to 84% of a
#: 24-frame clip, where the window and the whole segment give the same light anyway. Three quarters
#: keeps a constant light constant and still follows a light that turns steadily over the segment.
CHANGE_EXPLAINED = 0.75


#: A light switch in a shot is a jump between the means of 5 frames before and after it of at
#: least this many times the frame noise (:func:`~relightnet.temporal.offline.frame_noise`). A
#: threshold over the noise, not over the jump values, also finds a switch in a short shot,
#: where most frames are near the step.
SWITCH_NOISE = 8.0


def pool_window(fps: float, seconds: float = POOL_SECONDS) -> int:
    """Triangular pooling half-width in frames for a video at ``fps`` (at least 1).

    Example:
        >>> from relightnet.temporal.pooling import pool_window
        >>> pool_window(30.0, seconds=0.5), pool_window(1.0, seconds=0.1)
        (15, 1)
    """
    if not (fps > 0 and seconds > 0):
        raise InputError(f"pooling window: expected positive fps and seconds, got {fps!r}, {seconds!r}")
    return max(1, round(fps * seconds))


def pooling_weights(switches: torch.Tensor, window: int | None = None, windowed: torch.Tensor | None = None
                    ) -> torch.Tensor:
    """(T, T) weights: how much frame t's evidence counts for frame u.

    Args:
        switches: (T,) bool, True on the first frame of each new segment.
        window: None: every frame of the segment counts the same; else frames closer than
            ``window`` count with triangular weights ``1 − |u − t| / window``.
        windowed: (T,) bool, or None (every frame): the frames u whose weights are the window's;
            the others keep their whole segment's.

    Returns:
        (T, T) float64, zero across segment boundaries.
    """
    check_shape(switches, ["T"], name="switches")
    seg = switches.long().cumsum(0)
    same = (seg[:, None] == seg[None, :]).double()
    if window is None:
        return same
    if int(window) != window or window < 1:
        raise InputError(f"pooling window: expected a positive number of frames, got {window!r}")
    t = torch.arange(switches.shape[0], dtype=torch.float64)
    tri = same * (1 - (t[:, None] - t[None, :]).abs() / window).clamp_min(0)
    if windowed is None:
        return tri
    check_shape(windowed, [switches.shape[0]], name="windowed frames")
    return torch.where(windowed.bool()[:, None], tri, same)


def changing_segments(lights: torch.Tensor, switches: torch.Tensor, explained: float = CHANGE_EXPLAINED
                      ) -> torch.Tensor:
    """Which segments' light changes over time (the rest are taken as one constant light).

    A segment of at least 4 frames changes when the least-squares quadratic in time through its
    lights explains at least ``explained`` of
    their scatter about the segment's mean (:func:`~relightnet.temporal.distance.light_distance`
    squared, summed over the frames).

    Args:
        lights: (T, K, 3) per-frame lights.
        switches: (T,) bool, True on the first frame of each new segment.
        explained: the share in (0, 1).

    Returns:
        (T,) bool, True on every frame of a changing segment.
    """
    dims = check_shape(lights, ["T", "K", 3], name="lights")
    check_shape(switches, [dims["T"]], name="switches")
    if not 0 < explained < 1:
        raise InputError(f"explained share: expected a number in (0, 1), got {explained!r}")
    x = lights.double()
    starts = [0] + [int(i) for i in torch.nonzero(switches).flatten() if int(i) > 0] + [dims["T"]]
    out = torch.zeros(dims["T"], dtype=torch.bool)
    for a, b in zip(starts[:-1], starts[1:], strict=True):
        if b - a < 4:
            continue
        seg = x[a:b]
        u = torch.linspace(-1, 1, b - a, dtype=torch.float64)
        V = torch.stack([torch.ones_like(u), u, u * u], 1)  # the quadratic's basis: O(T), no (T, T) smoother
        fit = (V @ torch.linalg.lstsq(V, seg.flatten(1)).solution).view_as(seg)
        about_mean = light_distance(seg, seg.mean(0, keepdim=True)).square().sum()
        left = light_distance(seg, fit).square().sum()
        out[a:b] = bool(about_mean > 0) and bool(left <= (1 - explained) * about_mean)
    return out


def pool_shot_lights(evidence: Evidence, prior: torch.Tensor | None = None, reg: float = 1e-2,
                     window: int | None = None, switches="auto", change_window: int | None = None,
                     colour: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Lights of a whole video from its per-frame evidence (offline).

    Args:
        evidence: per-frame :class:`Evidence`, ``M`` (T, 3, K, K), ``r`` (T, 3, K).
        prior: (T, K, 3) per-frame prior lights (the hybrid's head), pooled with the same weights; or None.
        reg: the solve's λ (the network's ``solve_reg``).
        window: see :func:`pooling_weights` (None: one light per segment).
        change_window: with ``window`` None: the segments whose light changes
            (:func:`changing_segments` of the per-frame lights) are pooled over this window of frames
            instead (None: every segment keeps one light).
        switches: ``"auto"`` (detected on the per-frame lights: :func:`~relightnet.temporal.offline.detect_switches`
            with :data:`SWITCH_NOISE`, and with ``colour`` also the steps of the frames' colour:
            :func:`~relightnet.temporal.switches.colour_switches`), ``None`` (one segment) or a (T,)
            bool tensor.
        colour: (T, 3) the frames' mean linear colours (:func:`~relightnet.temporal.frame_colour`), or None.

    Returns:
        ``(pooled (T, K, 3), per_frame (T, K, 3), switches (T,) bool)``.

    Example:
        Four frames of one shot, each seeing half of the person, share the light of all their pixels:

        >>> import torch
        >>> from relightnet.sh import light_evidence
        >>> from relightnet.temporal import pool_shot_lights
        >>> g = torch.Generator().manual_seed(0)
        >>> T = torch.randn(4, 9, 8, 8, generator=g)
        >>> A = torch.rand(4, 3, 8, 8, generator=g)
        >>> L = torch.randn(9, 3, generator=g)
        >>> image = A * torch.einsum("tkhw,kc->tchw", T, L)
        >>> ev = light_evidence(image, A, T, torch.ones(4, 1, 8, 8))
        >>> pooled, per_frame, switches = pool_shot_lights(ev, reg=1e-8, switches=None)
        >>> pooled.shape, switches.tolist()
        (torch.Size([4, 9, 3]), [False, False, False, False])
        >>> torch.allclose(pooled, L.expand(4, 9, 3), atol=1e-4)
        True
    """
    dims = check_shape(evidence.M, ["T", 3, "K", "K"], name="evidence M")
    per_frame = solve_light(evidence, prior, reg)
    if isinstance(switches, str) and switches == "auto":
        switches = detect_switches(per_frame.double(), eps=None, noise=SWITCH_NOISE)
        if colour is not None:
            check_shape(colour, [dims["T"], "C"], name="frame colours")
            switches = merge_switches(switches, colour_switches(colour, noise=SWITCH_NOISE))
    elif switches is None:
        switches = torch.zeros(dims["T"], dtype=torch.bool)
    else:
        switches = torch.as_tensor(switches, dtype=torch.bool)
        check_shape(switches, [dims["T"]], name="switches")
    windowed = None
    if window is None and change_window is not None:
        window, windowed = change_window, changing_segments(per_frame, switches)
    t_len, k = dims["T"], dims["K"]
    parts = [evidence.M.double().flatten(1), evidence.r.double().flatten(1), torch.ones(t_len, 1, dtype=torch.float64)]
    if prior is not None:
        parts.append(prior.double().flatten(1))
    sums = pooled_sums(torch.cat(parts, 1), switches, window, windowed)  # float64, columns: M, r, Σw, prior
    m_end = 3 * k * k
    n_col = m_end + 3 * k
    M, r = sums[:, :m_end].view(t_len, 3, k, k), sums[:, m_end:n_col].view(t_len, 3, k)
    pooled_prior = None
    if prior is not None:
        pooled_prior = (sums[:, n_col + 1:] / sums[:, n_col:n_col + 1]).view_as(prior).float()
    pooled = solve_light(Evidence(M, r), pooled_prior, reg)  # pooled and solved in float64
    return pooled.float(), per_frame, switches


def pooled_sums(x: torch.Tensor, switches: torch.Tensor, window: int | None = None,
                windowed: torch.Tensor | None = None) -> torch.Tensor:
    """``pooling_weights(switches, window, windowed) @ x`` without the (T, T) weights: a whole segment's
    sum, or a triangular window's (a convolution over the segment's frames), in O(T · window) memory.

    Args:
        x: (T, D) per-frame values (e.g. the flattened evidence).
        switches, window, windowed: as for :func:`pooling_weights`.

    Returns:
        (T, D) float64.
    """
    dims = check_shape(x, ["T", "D"], name="pooled values")
    check_shape(switches, [dims["T"]], name="switches")
    if window is not None and (int(window) != window or window < 1):
        raise InputError(f"pooling window: expected a positive number of frames, got {window!r}")
    x = x.double()
    out = torch.empty_like(x)
    starts = [0] + [int(i) for i in torch.nonzero(switches).flatten() if int(i) > 0] + [dims["T"]]
    tri = None
    if window is not None:
        j = torch.arange(1 - int(window), int(window), dtype=torch.float64)
        tri = (1 - j.abs() / window).expand(dims["D"], 1, -1)
    for a, b in zip(starts[:-1], starts[1:], strict=True):
        whole = x[a:b].sum(0, keepdim=True).expand(b - a, -1)
        if tri is None:
            out[a:b] = whole
            continue
        slid = F.conv1d(x[a:b].T[None], tri, padding=int(window) - 1, groups=dims["D"])[0].T
        rows = torch.ones(b - a, dtype=torch.bool) if windowed is None else windowed[a:b].bool()
        out[a:b] = torch.where(rows[:, None], slid, whole)
    return out


def pooled_step(light: torch.Tensor, evidence: Evidence, prior: torch.Tensor | None, state: torch.Tensor,
                is_first: torch.Tensor | None, alpha: float = 0.05, reg: float = 1e-2, eps: float = 3.0,
                persist: int = 2, weights: torch.Tensor | None = None):
    """One causal step of :class:`PooledSolve`.

    Args:
        light: (B, K, 3) this frame's own solve (what the gate tests).
        evidence: this frame's :class:`Evidence` (``M`` (B, 3, K, K), ``r`` (B, 3, K)).
        prior: (B, K, 3) this frame's prior, or None.
        state: (B, K + 6, K, 3): pooled M (K slots, ``M[c, i, j]`` at ``[i, j, c]``), pooled r,
            pooled prior, frames pooled (a constant slot), gate (previous output, scale, count).
        is_first: (B,) restart flags, or None.
        alpha: the smallest weight of a new frame in the running mean.
        reg, eps, persist, weights: the solve's λ; the gate's options (:func:`gate_step`).

    Returns:
        ``(y (B, K, 3), new_state)``.
    """
    k = light.shape[-2]
    M_prev, r_prev, p_prev = state[:, :k].permute(0, 3, 1, 2), state[:, k].transpose(1, 2), state[:, k + 1]
    count = state[:, k + 2, 0, 0]
    _, first, switch, outlier, scale, gcount = gate_step(light, state[:, k + 3:], is_first, eps, persist,
                                                         weights=weights)
    restart = first | switch
    n = torch.where(restart, torch.ones_like(count), torch.where(outlier, count, count + 1))
    a = torch.where(outlier, torch.zeros_like(n), torch.maximum(1 / n, torch.full_like(n, alpha)))
    a = torch.where(restart, torch.ones_like(a), a)
    # Pooled in float64 and solved so; the state keeps its own dtype (float32 in the ONNX graph's interface).
    a64 = a.double()
    M_new = (1 - a64)[:, None, None, None] * M_prev.double() + a64[:, None, None, None] * evidence[0].double()
    r_new = (1 - a64)[:, None, None] * r_prev.double() + a64[:, None, None] * evidence[1].double()
    p = light if prior is None else prior
    p_new = (1 - a)[:, None, None] * p_prev + a[:, None, None] * p
    y = solve_light(Evidence(M_new, r_new), p_new if prior is not None else None, reg)
    ones = torch.ones_like(light)
    M_new, r_new = M_new.to(state.dtype), r_new.to(state.dtype)
    new_state = torch.cat([M_new.permute(0, 2, 3, 1), r_new.transpose(1, 2)[:, None], p_new[:, None],
                           (n[:, None, None] * ones)[:, None], y[:, None], (scale[:, None, None] * ones)[:, None],
                           (gcount[:, None, None] * ones)[:, None]], 1)
    return y, new_state


class PooledSolve(CausalFilter):
    """Causal shot pooling of the light solve's evidence (module docstring).

    ``forward(light (B, K, 3), state (B, K + 6, K, 3), is_first (B,), evidence=..., prior=None) -> (y, state)``.
    The state size depends on K, so ``lmax`` is given at construction.
    """

    uses_evidence = True

    def __init__(self, alpha: float = 0.05, reg: float = 1e-2, eps: float = 3.0, persist: int = 2,
                 lmax: int = 2) -> None:
        super().__init__()
        self.register_buffer("weights", filter_weights(lmax), persistent=False)
        self.alpha = check_alpha(alpha)
        self.reg = check_positive(reg, "reg")
        self.eps = check_positive(eps, "eps")
        if isinstance(persist, bool) or int(persist) != persist or persist < 1:
            raise InputError(f"persist: expected a positive integer, got {persist!r}")
        self.persist = int(persist)
        self.state_size = (lmax + 1) ** 2 + 6

    def forward(self, x, state=None, is_first=None, evidence: Evidence | None = None, prior=None):
        if evidence is None:
            raise InputError("pooled smoothing needs the light solve's evidence (a solve or hybrid network)")
        state, is_first = self._prepare(x, state, is_first)
        return pooled_step(x, evidence, prior, state, is_first, self.alpha, self.reg, self.eps, self.persist,
                           self.weights)
