"""Fit Anny to a photo's or a video's evidence (:class:`Observations`).

Per window of frames (all frames of a photo; ``window`` frames of a video, batched), Adam
minimises per frame

    w_2d·E_2d + w_3d·E_3d + w_sil·E_sil + w_lim·limits + w_rest·rest + w_acc·acceleration

(:mod:`.terms`, :mod:`.prior`): first the root rotation and translation alone (the first
quarter of the iterations, no silhouette), then every fitted bone. A video's first window
also fits the shape (:data:`SHAPE_NAMES`, shared over the shot, pulled toward the defaults);
later windows keep it, start from the previous window's last pose, orientation included (a
warm start), and take
``warm_iters`` iterations; their acceleration term includes the two frames before them.
Afterwards :func:`relightnet.fit.smooth_motion` smooths the whole track.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import torch

from ..body.anny_model import PHENOTYPES
from ..checks import InputError
from .body_model import SHAPE_NAMES, FitBody, phenotype_from_free
from .camera import project_points
from .init import initial_orientation, initial_translation
from .landmarks import landmark_weights
from .observe import Observations, world_to_view_axes
from .prior import FIT_BONES, limit_bounds, limit_penalty, rest_penalty
from .terms import acceleration_term, person_scale, reprojection_term, silhouette_targets, silhouette_term, world_term

logger = logging.getLogger(__name__)

__all__ = ["FitWeights", "FitResult", "fit_observations", "MAX_WINDOW_PIXELS"]


@dataclass(frozen=True)
class FitWeights:
    """Weights of the fit's terms (each term is dimensionless, :mod:`relightnet.fit.terms`)."""

    reprojection: float = 1e4
    world: float = 1.0
    silhouette: float = 1e4
    limits: float = 100.0
    rest: float = 0.3
    smooth: float = 0.05
    shape: float = 0.5


@dataclass(frozen=True, eq=False)
class FitResult:
    """A fitted track in the camera's view space.

    Attributes:
        pose: (T, N, 3) rotation vectors of :data:`relightnet.fit.FIT_BONES` (root: orientation to the camera).
        trans: (T, 3) translations (view space, metres).
        phenotype: (6,) in :data:`relightnet.body.PHENOTYPES` order.
        intrinsics: ``(fx, fy, cx, cy)``; size: (H, W).
        residual_2d: (T,) weighted RMS landmark error as a fraction of the person's height.
        interpolated: (T,) bool, frames where no person was found.
        seconds: wall time of the fit.
    """

    pose: torch.Tensor
    trans: torch.Tensor
    phenotype: torch.Tensor
    intrinsics: tuple[float, float, float, float]
    size: tuple[int, int]
    residual_2d: torch.Tensor
    interpolated: torch.Tensor
    seconds: float


@dataclass
class _Window:
    sub: torch.Tensor
    trans: torch.Tensor
    free: torch.Tensor


def _evidence(fb: FitBody, obs: Observations, start: int, stop: int) -> dict:
    o = obs.slice(start, stop)
    w = landmark_weights(o.landmarks[..., 3], fb.landmarks.mapped)
    ev = {"lm": o.landmarks, "w": w, "world": world_to_view_axes(o.world), "scale": person_scale(o.landmarks, w)}
    ev["sil"] = silhouette_targets(o.masks.unpack()) if o.masks is not None else None  # this window's only
    return ev


def _frame_losses(fb, win, ev, rest, intr, wts: FitWeights, bounds, before, use_sil: bool) -> tuple:
    pts, sv = fb.points(win.sub, win.trans, rest)
    e2d = reprojection_term(pts, ev["lm"], ev["w"], intr, ev["scale"])
    total = wts.reprojection * e2d + wts.world * world_term(pts, ev["world"], ev["w"])
    total = total + wts.limits * limit_penalty(win.sub, *bounds) + wts.rest * rest_penalty(win.sub)
    if use_sil and ev["sil"] is not None:
        total = total + wts.silhouette * silhouette_term(project_points(sv, intr), ev["sil"], ev["scale"])
    if wts.smooth > 0:
        total = total + wts.smooth * acceleration_term(pts, before)
    return total, e2d, pts


#: Pixels of silhouette evidence one window holds (frames × H × W; a float32 distance map each): 8 frames at
#: the 12.5 MP pixel limit, 400 MB. A longer window of such frames is refused, not allowed to pass the budget.
MAX_WINDOW_PIXELS = 100_000_000

#: A shape fit recomputes the rest body (the costly part) and steps the shape every this many iterations.
SHAPE_EVERY = 5


def _optimise(fb, win: _Window, ev, base, intr, wts, iters: int, fit_shape: bool, before) -> tuple:
    bounds = limit_bounds(win.sub.dtype)
    params = [win.sub, win.trans] + ([win.free] if fit_shape else [])
    for p in params:
        p.requires_grad_(True)
    opt = torch.optim.Adam([{"params": [win.sub], "lr": 0.03}, {"params": [win.trans], "lr": 0.01}])
    opt_shape = torch.optim.Adam([win.free], lr=0.1) if fit_shape else None
    n_global = iters // 4
    with torch.no_grad():
        rest = fb.rest(phenotype_from_free(win.free, base))
    for i in range(iters):
        shape_step = fit_shape and i >= n_global and i % SHAPE_EVERY == 0
        if shape_step:
            rest = fb.rest(phenotype_from_free(win.free, base))
        opt.zero_grad(set_to_none=True)
        total, _, _ = _frame_losses(fb, win, ev, rest, intr, wts, bounds, before, use_sil=i >= n_global)
        loss = total.sum()
        if shape_step:
            opt_shape.zero_grad(set_to_none=True)
            loss = loss + wts.shape * win.free.square().sum()
        loss.backward()
        if i < n_global:
            win.sub.grad[:, 1:] = 0
        opt.step()
        if shape_step:
            opt_shape.step()
            with torch.no_grad():
                rest = fb.rest(phenotype_from_free(win.free, base))
    with torch.no_grad():
        rest = fb.rest(phenotype_from_free(win.free, base))
        _, e2d, pts = _frame_losses(fb, win, ev, rest, intr, wts, bounds, before, use_sil=True)
    for p in params:
        p.requires_grad_(False)
    return e2d.sqrt(), pts


def _start(fb: FitBody, ev: dict, base, free, intr, prev_sub) -> _Window:
    """Initial window: the pose of ``prev_sub`` (the previous window's last frame) or, for the first
    window, the rest pose turned as the landmarks say; the translation from the landmarks."""
    B = ev["lm"].shape[0]
    with torch.no_grad():
        rest = fb.rest(phenotype_from_free(free, base))
        zero = torch.zeros(1, len(FIT_BONES), 3)
        rest_pts, _ = fb.points(zero, torch.zeros(1, 3), rest)
        if prev_sub is None:  # the first window: the orientation from the landmarks, the rest pose
            sub = zero.expand(B, -1, -1).clone()
            sub[:, 0] = initial_orientation(rest_pts[0], ev["world"], ev["w"])
        else:  # later windows: the previous frame's pose, orientation included (no front/back flips)
            sub = prev_sub.expand(B, -1, -1).clone()
        pts, _ = fb.points(sub, torch.zeros(B, 3), rest)
        trans = initial_translation(pts, ev["lm"], ev["w"], intr)
    return _Window(sub, trans, free.clone())


def fit_observations(obs: Observations, intrinsics, body: FitBody | None = None, iters: int = 120,
                     warm_iters: int = 50, window: int = 8, fit_shape: bool = True,
                     weights: FitWeights = FitWeights()) -> FitResult:
    """Fit Anny to T frames of evidence (T = 1: a photo).

    Args:
        obs: the :class:`Observations`.
        intrinsics: ``(fx, fy, cx, cy)`` of the frames (:mod:`relightnet.fit.camera`).
        body: a :class:`FitBody` (made here when None; pass one for many fits).
        iters: Adam iterations of the first window; warm_iters: of each later window.
        window: frames fitted together (at most :data:`MAX_WINDOW_PIXELS` pixels of them).
        fit_shape: also fit height, weight and proportions (on the first window).

    Returns:
        :class:`FitResult` (unsmoothed; see :func:`relightnet.fit.smooth_motion`).

    Raises:
        InputError: iterations or window below 1; a window of more pixels than :data:`MAX_WINDOW_PIXELS`.
    """
    if iters < 1 or warm_iters < 1 or window < 1:
        raise InputError(f"fit: iters, warm_iters and window must be >= 1, got {iters}, {warm_iters}, {window}")
    H, W = (int(x) for x in obs.size)
    n = min(window, obs.n_frames)
    if obs.masks is not None and n > 1 and n * H * W > MAX_WINDOW_PIXELS:
        raise InputError(f"fit: a window of {n} frames of {W}x{H} would hold {n * H * W * 4 / 2**30:.1f} GiB of "
                         f"silhouette distance maps; at most {max(MAX_WINDOW_PIXELS // (H * W), 1)} frames of this "
                         "size are fitted together (a smaller --window)")
    t0 = time.perf_counter()
    fb = body if body is not None else FitBody()
    base = torch.tensor([PHENOTYPES[n][2] for n in PHENOTYPES])
    free = torch.zeros(len(SHAPE_NAMES))
    for j, n in enumerate(SHAPE_NAMES):  # start at the defaults: sigmoid⁻¹ of their place in the range
        lo, hi, d = PHENOTYPES[n]
        free[j] = torch.logit(torch.tensor((d - lo) / (hi - lo)))
    subs, transs, res, prev, before = [], [], [], None, None
    for start in range(0, obs.n_frames, window):
        stop = min(start + window, obs.n_frames)
        ev = _evidence(fb, obs, start, stop)
        win = _start(fb, ev, base, free, intrinsics, prev)
        first = start == 0
        r, pts = _optimise(fb, win, ev, base, intrinsics, weights, iters if first else warm_iters,
                           fit_shape and first, before)
        free = win.free.detach()
        subs.append(win.sub.detach())
        transs.append(win.trans.detach())
        res.append(r)
        prev, before = win.sub[-1:].detach(), pts[-2:].detach()
        del ev  # this window's distance maps go before the next window's are made (two would be 800 MB at 12.5 MP)
        logger.debug("fit: frames %d-%d, residual %.4f", start, stop - 1, float(r.mean()))
    phen = phenotype_from_free(free, base)[0].detach()
    return FitResult(torch.cat(subs), torch.cat(transs), phen, tuple(float(x) for x in intrinsics),
                     tuple(obs.size), torch.cat(res), ~obs.found.bool(), time.perf_counter() - t0)
