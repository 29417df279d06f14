"""Fit Anny to a photo's or a video's evidence (:class:`Observations`).

Per window of frames (all frames of a photo; ``window`` frames of a video, batched), Adam
minimises per frame

    w_2d·E_2d + w_3d·E_3d + w_sil·E_sil + w_lim·limits + w_rest·rest + w_acc·acceleration

(:mod:`.terms`, :mod:`.prior`): first the root rotation and translation alone (the first
quarter of the iterations, no silhouette), then every fitted bone. A video's first window
also fits the shape (:data:`SHAPE_NAMES`, shared over the shot, pulled toward the defaults);
later windows keep it, start from the previous window's last pose (a warm start) with its
orientation turned, frame by frame, as the world landmarks' torso turns since that frame
(:func:`relightnet.fit.relative_turn`: a person turning in place is followed, a left/right
swap is not), and take ``warm_iters`` iterations (or fewer with ``tol``: an early stop);
their acceleration term includes the two frames before them.
Afterwards :func:`relightnet.fit.smooth_motion` smooths the whole track.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import torch

from ..body.anny_model import PHENOTYPES
from ..body.base import matrix_to_rotvec, rotvec_to_matrix
from ..checks import InputError
from .body_model import SHAPE_NAMES, FitBody, phenotype_from_free, rest_near
from .camera import project_points
from .init import initial_orientation, initial_translation, relative_turn
from .landmarks import landmark_weights
from .observe import Observations, world_to_view_axes
from .prior import FIT_BONES, limit_bounds, limit_penalty, rest_penalty
from .terms import (
                    acceleration_term,
                    outline_matches,
                    person_scale,
                    reprojection_term,
                    silhouette_targets,
                    silhouette_term,
                    world_term,
)

logger = logging.getLogger(__name__)

__all__ = ["FitWeights", "FitResult", "fit_observations", "MAX_WINDOW_PIXELS", "MAX_FIT_FRAMES"]


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
    # this window's only (the next window's are made after these are dropped), from its masks at the working
    # resolution (stored so when the masks were packed for this window; resampled here otherwise)
    ev["sil"] = silhouette_targets(o.masks.working()[0], size=obs.size, height=None) if o.masks is not None else None
    return ev


#: The silhouette's outline points are matched to their nearest vertices every this many steps.
MATCH_EVERY = 4


def _frame_losses(fb, win, ev, rest, intr, wts: FitWeights, bounds, before, use_sil: bool, step: int = 0) -> tuple:
    pts, sv = fb.points(win.sub, win.trans, rest)
    e2d = reprojection_term(pts, ev["lm"], ev["w"], intr, ev["scale"])
    total = wts.reprojection * e2d + wts.world * world_term(pts, ev["world"], ev["w"])
    total = total + wts.limits * limit_penalty(win.sub, *bounds) + wts.rest * rest_penalty(win.sub)
    if use_sil and ev["sil"] is not None:
        px = project_points(sv, intr)
        if step % MATCH_EVERY == 0 or "matches" not in ev:
            ev["matches"] = outline_matches(px, ev["sil"])
        total = total + wts.silhouette * silhouette_term(px, ev["sil"], ev["scale"], ev["matches"])
    if wts.smooth > 0:
        total = total + wts.smooth * acceleration_term(pts, before)
    return total, e2d, pts


#: Pixels of silhouette evidence one window holds at the frames' size (frames × H × W: its float32 distance
#: maps at the working resolution, which is the frames' size for a person under 240 px tall): 8 frames at the
#: 12.5 MP pixel limit, 400 MB. A longer window of such frames is refused, not allowed to pass the budget.
MAX_WINDOW_PIXELS = 100_000_000

#: Frames of one video fit (5.5 minutes at 30 fps). What a fit holds per frame for the whole video is
#: its packed mask at the working resolution (at most :data:`relightnet.fit.MAX_FRAME_BYTES`, 28.5 KiB,
#: for a mask that does not compress; ~1 KB for a person's), its landmarks and its fitted pose (~4 KB),
#: and the motion made of it (~10 KB a frame, measured at 10,000 frames): at most ~0.45 GiB at this limit,
#: on top of the ~1.4 GiB a 12.5 MP frame's segmentation and window take, so a fit within the limits
#: stays within the 2 GiB budget (SECURITY.md, "Memory budget"). Longer videos are refused before any
#: work (cut them into parts).
MAX_FIT_FRAMES = 10_000

#: A shape fit steps the shape every this many iterations, on a first-order model of the rest
#: body (:func:`relightnet.fit.rest_near`) re-linearised every :data:`RELINEARISE_EVERY`
#: iterations (each linearisation costs four rest bodies; the exact rest body ends the window).
SHAPE_EVERY = 5
RELINEARISE_EVERY = 20
#: Early stop of a warm-started window (``tol`` of :func:`fit_observations`; the first window,
#: which also fits the shape, runs all its iterations): after the root-only phase it stops when
#: its loss has not fallen by the fraction ``tol`` in :data:`PATIENCE` iterations. Off by default:
#: on a moving person the loss keeps falling (no stop), and on a person standing still a window
#: that stopped left a jump at the window's start (raw acceleration error 15 against 7.5 mm/frame²).
PATIENCE = 6


def _optimise(fb, win: _Window, ev, base, intr, wts, iters: int, fit_shape: bool, before, tol: float) -> tuple:
    bounds = limit_bounds(win.sub.dtype)
    params = [win.sub, win.trans] + ([win.free] if fit_shape else [])
    for p in params:
        p.requires_grad_(True)
    opt = torch.optim.Adam([{"params": [win.sub], "lr": 0.03}, {"params": [win.trans], "lr": 0.01}])
    opt_shape = torch.optim.Adam([win.free], lr=0.1) if fit_shape else None
    n_global = iters // 4
    with torch.no_grad():
        rest = fb.rest(phenotype_from_free(win.free, base))
    best, since, lin_at = float("inf"), 0, None
    for i in range(iters):
        shape_step = fit_shape and i >= n_global and i % SHAPE_EVERY == 0
        if shape_step:
            if lin_at is None or i - lin_at >= RELINEARISE_EVERY:
                free0, lin_at = win.free.detach().clone(), i
                rest0, jac = fb.rest_linearised(free0, base)
            rest = rest_near(rest0, jac, win.free - free0)
        opt.zero_grad(set_to_none=True)
        total, _, _ = _frame_losses(fb, win, ev, rest, intr, wts, bounds, before, use_sil=i >= n_global, step=i)
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
                rest = rest_near(rest0, jac, win.free - free0)
        if i >= n_global and tol > 0 and not fit_shape:
            value = float(loss.detach())
            best, since = (value, 0) if value < best * (1 - tol) else (best, since + 1)
            if since >= PATIENCE:
                break
    with torch.no_grad():
        rest = fb.rest(phenotype_from_free(win.free, base))
        _, e2d, pts = _frame_losses(fb, win, ev, rest, intr, wts, bounds, before, use_sil=True)
    for p in params:
        p.requires_grad_(False)
    return e2d.sqrt(), pts


def _start(fb: FitBody, ev: dict, base, free, intr, prev: dict | None) -> _Window:
    """Initial window. The first: the rest pose turned as the landmarks say. Later ones: the
    previous window's last pose (``prev["sub"]``), its orientation turned by the torso's turn in
    the world landmarks since that frame (``prev["world"]``, ``prev["w"]``; no absolute front/back
    guess). The translation from the landmarks."""
    B = ev["lm"].shape[0]
    with torch.no_grad():
        rest = fb.rest(phenotype_from_free(free, base))
        zero = torch.zeros(1, len(FIT_BONES), 3)
        rest_pts, _ = fb.points(zero, torch.zeros(1, 3), rest)
        if prev is None:
            sub = zero.expand(B, -1, -1).clone()
            sub[:, 0] = initial_orientation(rest_pts[0], ev["world"], ev["w"])
        else:
            sub = prev["sub"].expand(B, -1, -1).clone()
            turn = relative_turn(torch.cat([prev["world"][None], ev["world"]]), torch.cat([prev["w"][None], ev["w"]]))
            sub[:, 0] = matrix_to_rotvec((turn @ rotvec_to_matrix(sub[:, 0])).double()).to(sub.dtype)
        pts, _ = fb.points(sub, torch.zeros(B, 3), rest)
        trans = initial_translation(pts, ev["lm"], ev["w"], intr)
    return _Window(sub, trans, free.clone())


def fit_observations(obs: Observations, intrinsics, body: FitBody | None = None, iters: int = 120,
                     warm_iters: int = 50, window: int = 8, fit_shape: bool = True,
                     weights: FitWeights = FitWeights(), tol: float = 0.0) -> FitResult:
    """Fit Anny to T frames of evidence (T = 1: a photo).

    Args:
        obs: the :class:`Observations`.
        intrinsics: ``(fx, fy, cx, cy)`` of the frames (:mod:`relightnet.fit.camera`).
        body: a :class:`FitBody` (made here when None; pass one for many fits).
        iters: Adam iterations of the first window; warm_iters: of each later window.
        window: frames fitted together (at most :data:`MAX_WINDOW_PIXELS` pixels of them).
        fit_shape: also fit height, weight and proportions (on the first window).
        tol: early stop of warm windows (:data:`PATIENCE`; 0: every iteration runs).

    The fit runs on one intra-op thread (torch's setting is restored afterwards): its tensors are
    small (a window's few hundred points), and a second thread only waited — with two threads on
    a shared 2-core machine the fit took 8–10× the CPU time and 7× the wall time of one.

    Returns:
        :class:`FitResult` (unsmoothed; see :func:`relightnet.fit.smooth_motion`).

    Raises:
        InputError: iterations or window below 1; a window of more pixels than :data:`MAX_WINDOW_PIXELS`;
            more frames than :data:`MAX_FIT_FRAMES`.
    """
    if iters < 1 or warm_iters < 1 or window < 1 or not 0 <= tol < 1:
        raise InputError(f"fit: iters, warm_iters and window must be >= 1 and tol in [0, 1), got {iters}, "
                         f"{warm_iters}, {window}, {tol}")
    if obs.n_frames > MAX_FIT_FRAMES:
        raise InputError(f"fit: {obs.n_frames} frames; at most {MAX_FIT_FRAMES} frames are fitted at once "
                         "(cut the video into parts)")
    H, W = (int(x) for x in obs.size)
    n = min(window, obs.n_frames)
    if obs.masks is not None and n > 1 and n * H * W > MAX_WINDOW_PIXELS:
        raise InputError(f"fit: a window of {n} frames of {W}x{H} would hold {n * H * W * 4 / 2**30:.1f} GiB of "
                         f"silhouette masks; at most {max(MAX_WINDOW_PIXELS // (H * W), 1)} frames of this "
                         "size are fitted together (a smaller --window)")
    t0, threads = time.perf_counter(), torch.get_num_threads()
    fb = body if body is not None else FitBody()
    torch.set_num_threads(1)
    try:
        subs, transs, res, phen = _fit_windows(fb, obs, intrinsics, iters, warm_iters, window, fit_shape, weights, tol)
    finally:
        torch.set_num_threads(threads)
    return FitResult(subs, transs, phen, tuple(float(x) for x in intrinsics), tuple(obs.size), res,
                     ~obs.found.bool(), time.perf_counter() - t0)


def _fit_windows(fb, obs, intrinsics, iters, warm_iters, window, fit_shape, weights, tol) -> tuple:
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
                           fit_shape and first, before, tol)
        free = win.free.detach()
        subs.append(win.sub.detach())
        transs.append(win.trans.detach())
        res.append(r)
        prev = {"sub": win.sub[-1:].detach(), "world": ev["world"][-1], "w": ev["w"][-1]}
        before = pts[-2:].detach()
        del ev  # this window's silhouette evidence goes before the next window's is made
        logger.debug("fit: frames %d-%d, residual %.4f", start, stop - 1, float(r.mean()))
    return torch.cat(subs), torch.cat(transs), torch.cat(res), phenotype_from_free(free, base)[0].detach()
