"""Fit Anny to a photo's or a video's evidence (:class:`Observations`).

Per window of frames (all frames of a photo; ``window`` frames of a video, batched), Adam
minimises per frame

    w_2d·E_2d + w_3d·E_3d + w_sil·E_sil + w_lim·limits + w_rest·rest + w_acc·acceleration

(:mod:`.terms`, :mod:`.prior`): first the root rotation and translation alone (the first
quarter of the iterations, no silhouette), then every fitted bone. A video's first window
also fits the shape (:data:`SHAPE_NAMES`, shared over the shot, pulled toward the defaults);
later windows keep it, start from the previous window's last pose (a warm start) with its
orientation turned, frame by frame, as the world landmarks' torso turns since that frame
(:func:`relightnet.fit.init.relative_turn`: a person turning in place is followed, a left/right
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
from ..threads import torch_threads
from .body_model import SHAPE_NAMES, FitBody, phenotype_from_free, rest_near
from .camera import project_points
from .init import initial_orientation, initial_translation, relative_turn
from .landmarks import landmark_weights
from .observe import Observations, world_to_view_axes
from .prior import FIT_BONES, limit_bounds, limit_penalty, rest_penalty
from .terms import (
                    SilhouetteTargets,
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
        pose: (T, N, 3) rotation vectors of :data:`relightnet.fit.body_model.FIT_BONES` (root: orientation to
            the camera).
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


@dataclass(frozen=True, eq=False)
class _Problem:
    """What every window of one fit shares.

    Attributes:
        body: the :class:`FitBody`.
        default_phenotype: (6,) the phenotype's defaults (:data:`relightnet.body.PHENOTYPES` order), which
            the fitted shape (:data:`SHAPE_NAMES`) replaces in part.
        intrinsics: ``(fx, fy, cx, cy)`` of the frames.
        weights: the terms' :class:`FitWeights`.
    """

    body: FitBody
    default_phenotype: torch.Tensor
    intrinsics: tuple
    weights: FitWeights


@dataclass(frozen=True, eq=False)
class _WindowEvidence:
    """What one window of B frames is fitted to.

    Attributes:
        landmarks: (B, 33, 5) pixel landmarks (:attr:`Observations.landmarks`).
        landmark_weights: (B, 33) each landmark's weight (0: unmapped or unseen).
        world: (B, 33, 3) world landmarks in view-space axes, metres.
        person_height: (B,) the person's height in pixels (the 2D terms' unit).
        silhouette: the masks' distance maps and outlines at the working resolution, or None (no masks).
    """

    landmarks: torch.Tensor
    landmark_weights: torch.Tensor
    world: torch.Tensor
    person_height: torch.Tensor
    silhouette: SilhouetteTargets | None


@dataclass(frozen=True, eq=False)
class _Carried:
    """What a window hands the next one (None in each field before the first window, but the shape).

    Attributes:
        shape_free: (S,) the unconstrained shape of :data:`SHAPE_NAMES` (fitted on the first window).
        last_pose: (1, N, 3) the last frame's pose of :data:`FIT_BONES` (the warm start).
        last_world: (33, 3) the last frame's world landmarks, view-space axes (the turn since it).
        last_weights: (33,) the last frame's landmark weights.
        points_before: (2, P, 3) the last two frames' fitted points (the acceleration term's history).
    """

    shape_free: torch.Tensor
    last_pose: torch.Tensor | None = None
    last_world: torch.Tensor | None = None
    last_weights: torch.Tensor | None = None
    points_before: torch.Tensor | None = None


@dataclass
class _Window:
    """The parameters one window optimises (updated in place by Adam).

    Attributes:
        pose: (B, N, 3) rotation vectors of :data:`FIT_BONES`.
        trans: (B, 3) translations, view space, metres.
        shape_free: (S,) the unconstrained shape (stepped on a shape-fitting window only).
    """

    pose: torch.Tensor
    trans: torch.Tensor
    shape_free: torch.Tensor


def _window_evidence(body: FitBody, obs: Observations, start: int, stop: int) -> _WindowEvidence:
    o = obs.slice(start, stop)
    weights = landmark_weights(o.landmarks[..., 3], body.landmarks.mapped)
    # this window's only (the next window's are made after these are dropped), from its masks at the working
    # resolution (stored so when the masks were packed for this window; resampled here otherwise)
    silhouette = (silhouette_targets(o.masks.working()[0], size=obs.size, height=None)
                  if o.masks is not None else None)
    return _WindowEvidence(o.landmarks, weights, world_to_view_axes(o.world), person_scale(o.landmarks, weights),
                           silhouette)


#: The silhouette's outline points are matched to their nearest vertices every this many steps.
MATCH_EVERY = 4


def _frame_losses(problem: _Problem, win: _Window, ev: _WindowEvidence, rest, bounds, before,
                  matches: torch.Tensor | None, step: int | None) -> tuple:
    """``(total (B,), reprojection (B,), points (B, P, 3), matches)``: each frame's loss. ``step``: the
    iteration (the outline is matched again every :data:`MATCH_EVERY` steps, and where ``matches`` is None);
    None: no silhouette term. ``matches``: (B, M) the outline's nearest vertices of an earlier step, or None."""
    wts = problem.weights
    pts, verts = problem.body.points(win.pose, win.trans, rest)
    e2d = reprojection_term(pts, ev.landmarks, ev.landmark_weights, problem.intrinsics, ev.person_height)
    total = wts.reprojection * e2d + wts.world * world_term(pts, ev.world, ev.landmark_weights)
    total = total + wts.limits * limit_penalty(win.pose, *bounds) + wts.rest * rest_penalty(win.pose)
    if step is not None and ev.silhouette is not None:
        px = project_points(verts, problem.intrinsics)
        if step % MATCH_EVERY == 0 or matches is None:
            matches = outline_matches(px, ev.silhouette)
        total = total + wts.silhouette * silhouette_term(px, ev.silhouette, ev.person_height, matches)
    if wts.smooth > 0:
        total = total + wts.smooth * acceleration_term(pts, before)
    return total, e2d, pts, matches


#: Pixels of silhouette evidence one window holds at the frames' size (frames × H × W: its float32 distance
#: maps at the working resolution, which is the frames' size for a person under 240 px tall): 8 frames at the
#: 12.5 MP pixel limit, 400 MB. A longer window of such frames is refused, not allowed to pass the budget.
MAX_WINDOW_PIXELS = 100_000_000

#: Frames of one video fit (5.5 minutes at 30 fps). What a fit holds per frame for the whole video is
#: its packed mask at the working resolution (at most :data:`relightnet.fit.masks.MAX_FRAME_BYTES`, 28.5 KiB,
#: for a mask that does not compress; ~1 KB for a person's), its landmarks and its fitted pose (~4 KB),
#: and the motion made of it (~10 KB a frame, measured at 10,000 frames): at most ~0.45 GiB at this limit,
#: on top of the ~1.4 GiB a 12.5 MP frame's segmentation and window take, so a fit within the limits
#: stays within the 2 GiB budget (SECURITY.md, "Memory budget"). Longer videos are refused before any
#: work (cut them into parts).
MAX_FIT_FRAMES = 10_000

#: A shape fit steps the shape every this many iterations, on a first-order model of the rest
#: body (:func:`relightnet.fit.body_model.rest_near`) re-linearised every :data:`RELINEARISE_EVERY`
#: iterations (each linearisation costs four rest bodies; the exact rest body ends the window).
SHAPE_EVERY = 5
RELINEARISE_EVERY = 20
#: Early stop of a warm-started window (``tol`` of :func:`fit_observations`; the first window,
#: which also fits the shape, runs all its iterations): after the root-only phase it stops when
#: its loss has not fallen by the fraction ``tol`` in :data:`PATIENCE` iterations. Off by default:
#: on a moving person the loss keeps falling (no stop), and on a person standing still a window
#: that stopped left a jump at the window's start (raw acceleration error 15 against 7.5 mm/frame²).
PATIENCE = 6


def _optimise(problem: _Problem, win: _Window, ev: _WindowEvidence, before, iters: int, fit_shape: bool,
              tol: float) -> tuple:
    """Adam on ``win`` (in place): ``(residual (B,), points (B, P, 3))`` at the end. ``before``:
    :attr:`_Carried.points_before`."""
    body, base = problem.body, problem.default_phenotype
    bounds = limit_bounds(win.pose.dtype)
    params = [win.pose, win.trans] + ([win.shape_free] if fit_shape else [])
    for p in params:
        p.requires_grad_(True)
    opt = torch.optim.Adam([{"params": [win.pose], "lr": 0.03}, {"params": [win.trans], "lr": 0.01}])
    opt_shape = torch.optim.Adam([win.shape_free], lr=0.1) if fit_shape else None
    n_root_only = iters // 4
    with torch.no_grad():
        rest = body.rest(phenotype_from_free(win.shape_free, base))
    best, since, linearised_at, matches = float("inf"), 0, None, None
    for i in range(iters):
        shape_step = fit_shape and i >= n_root_only and i % SHAPE_EVERY == 0
        if shape_step:
            if linearised_at is None or i - linearised_at >= RELINEARISE_EVERY:
                free_at, linearised_at = win.shape_free.detach().clone(), i
                rest_at, jacobian = body.rest_linearised(free_at, base)
            rest = rest_near(rest_at, jacobian, win.shape_free - free_at)
        opt.zero_grad(set_to_none=True)
        total, _, _, matches = _frame_losses(problem, win, ev, rest, bounds, before, matches,
                                             step=i if i >= n_root_only else None)
        loss = total.sum()
        if shape_step:
            opt_shape.zero_grad(set_to_none=True)
            loss = loss + problem.weights.shape * win.shape_free.square().sum()
        loss.backward()
        if i < n_root_only:
            win.pose.grad[:, 1:] = 0
        opt.step()
        if shape_step:
            opt_shape.step()
            with torch.no_grad():
                rest = rest_near(rest_at, jacobian, win.shape_free - free_at)
        if i >= n_root_only and tol > 0 and not fit_shape:
            value = float(loss.detach())
            best, since = (value, 0) if value < best * (1 - tol) else (best, since + 1)
            if since >= PATIENCE:
                break
    with torch.no_grad():
        rest = body.rest(phenotype_from_free(win.shape_free, base))
        _, e2d, pts, _ = _frame_losses(problem, win, ev, rest, bounds, before, None, step=0)
    for p in params:
        p.requires_grad_(False)
    return e2d.sqrt(), pts


def _start(problem: _Problem, ev: _WindowEvidence, carried: _Carried) -> _Window:
    """Initial window. The first: the rest pose turned as the landmarks say. Later ones: the
    previous window's last pose (:attr:`_Carried.last_pose`), its orientation turned by the torso's
    turn in the world landmarks since that frame (``last_world``, ``last_weights``; no absolute
    front/back guess). The translation from the landmarks."""
    body, B = problem.body, ev.landmarks.shape[0]
    with torch.no_grad():
        rest = body.rest(phenotype_from_free(carried.shape_free, problem.default_phenotype))
        zero = torch.zeros(1, len(FIT_BONES), 3)
        rest_pts, _ = body.points(zero, torch.zeros(1, 3), rest)
        if carried.last_pose is None:
            pose = zero.expand(B, -1, -1).clone()
            pose[:, 0] = initial_orientation(rest_pts[0], ev.world, ev.landmark_weights)
        else:
            pose = carried.last_pose.expand(B, -1, -1).clone()
            turn = relative_turn(torch.cat([carried.last_world[None], ev.world]),
                                 torch.cat([carried.last_weights[None], ev.landmark_weights]))
            pose[:, 0] = matrix_to_rotvec((turn @ rotvec_to_matrix(pose[:, 0])).double()).to(pose.dtype)
        pts, _ = body.points(pose, torch.zeros(B, 3), rest)
        trans = initial_translation(pts, ev.landmarks, ev.landmark_weights, problem.intrinsics)
    return _Window(pose, trans, carried.shape_free.clone())


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
    t0 = time.perf_counter()
    default_phenotype = torch.tensor([PHENOTYPES[name][2] for name in PHENOTYPES])
    problem = _Problem(body if body is not None else FitBody(), default_phenotype, intrinsics, weights)
    with torch_threads(1):
        pose, trans, residual, phenotype = _fit_windows(problem, obs, iters, warm_iters, window, fit_shape, tol)
    return FitResult(pose, trans, phenotype, tuple(float(x) for x in intrinsics), tuple(obs.size), residual,
                     ~obs.found.bool(), time.perf_counter() - t0)


def _fit_windows(problem: _Problem, obs: Observations, iters: int, warm_iters: int, window: int, fit_shape: bool,
                 tol: float) -> tuple:
    """``(pose (T, N, 3), trans (T, 3), residual (T,), phenotype (6,))``, window after window."""
    free = torch.zeros(len(SHAPE_NAMES))
    for j, n in enumerate(SHAPE_NAMES):  # start at the defaults: sigmoid⁻¹ of their place in the range
        lo, hi, d = PHENOTYPES[n]
        free[j] = torch.logit(torch.tensor((d - lo) / (hi - lo)))
    poses, transs, residuals, carried = [], [], [], _Carried(free)
    for start in range(0, obs.n_frames, window):
        stop = min(start + window, obs.n_frames)
        ev = _window_evidence(problem.body, obs, start, stop)
        win = _start(problem, ev, carried)
        first = start == 0
        residual, pts = _optimise(problem, win, ev, carried.points_before, iters if first else warm_iters,
                                  fit_shape and first, tol)
        poses.append(win.pose.detach())
        transs.append(win.trans.detach())
        residuals.append(residual)
        carried = _Carried(win.shape_free.detach(), win.pose[-1:].detach(), ev.world[-1], ev.landmark_weights[-1],
                           pts[-2:].detach())
        del ev  # this window's silhouette evidence goes before the next window's is made
        logger.debug("fit: frames %d-%d, residual %.4f", start, stop - 1, float(residual.mean()))
    phenotype = phenotype_from_free(carried.shape_free, problem.default_phenotype)[0].detach()
    return torch.cat(poses), torch.cat(transs), torch.cat(residuals), phenotype
