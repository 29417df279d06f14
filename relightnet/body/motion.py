"""Procedural motion for Anny: walk, turn in place, idle, arm raise.

``make_motion(kind, n_frames, fps, seed, **opts)`` returns pose parameters that
:class:`relightnet.body.AnnyBody` takes directly (the T frames become the batch):
``{"pose": {bone: (T, 3)}, "trans": (T, 3)}``, rotation vectors in world axes.

Every curve is a sum of sinusoids (C^∞) or a clamped smoothstep (C¹), so poses are
C¹ in time. The seed draws amplitudes (×0.85–1.15 per group), phase, and tempo; any
``opts`` given explicitly override the draw.

Anny's rig, as found by rotating one bone at a time in world axes (the parent chain
at rest) and watching the child joints — x = the person's left, y = up, z = forward:

- hip ``upperleg01.{L,R}``: −x swings the thigh forward (flexion), +x backward;
  knee ``lowerleg01.*``: +x bends the knee (shin goes back); ankle ``foot.*``: −x lifts the
  toes; ``upperleg02``/``lowerleg02`` are mid-limb twist bones;
- shoulder ``upperarm01.{L,R}``: +z raises the left arm sideways, −z the right one; −x
  swings a hanging arm forward; elbow ``lowerarm01.*``: −x bends a hanging forearm forward;
  ``upperarm02``/``lowerarm02`` are twist bones; ``wrist.*`` the hands;
- torso: ``root`` (pelvis, global orientation), then ``spine05`` (lowest) … ``spine01``
  (chest), ``neck01``–``neck03``, ``head``; +x bends forward, +y turns toward the person's
  left (counter-clockwise seen from above), +z tilts the top toward the person's right (−x).

A delta is applied in its parent's posed axes, so these directions are body-relative: the
knee still bends with +x when the thigh is swung or the whole body turned.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from ..checks import InputError
from ..names import MOTION_KINDS
from .anny_model import pose_preset
from .base import compose_rotvecs

__all__ = ["make_motion", "MOTION_KINDS"]


_X, _Y, _Z = np.eye(3)


class _Pose:
    """Per-bone lists of (T, 3) rotation vectors, composed in the order they are added."""

    def __init__(self, n: int, base: str | None):
        self.n = n
        self.rot: dict[str, list[np.ndarray]] = {}
        if base:
            for bone, rv in pose_preset(base).items():
                self.add(bone, np.broadcast_to(np.asarray(rv, dtype=np.float64), (n, 3)))

    def add(self, bone: str, rotvec: np.ndarray) -> None:
        self.rot.setdefault(bone, []).append(np.asarray(rotvec, dtype=np.float64))

    def about(self, bone: str, axis: np.ndarray, angle: np.ndarray) -> None:
        """Rotate ``bone`` by ``angle`` (T,) radians about world ``axis``, after what is there."""
        self.add(bone, np.asarray(angle, dtype=np.float64)[:, None] * axis[None, :])

    def tensors(self) -> dict[str, torch.Tensor]:
        out = {}
        for bone, seq in self.rot.items():
            r = torch.tensor(seq[0], dtype=torch.float64)
            for nxt in seq[1:]:
                r = compose_rotvecs(r, torch.tensor(nxt, dtype=torch.float64))
            out[bone] = r.to(torch.float32).contiguous()
        return out


def _smoothstep(u: np.ndarray) -> np.ndarray:
    """C¹ ease 0 → 1 on [0, 1] (zero slope at both ends), clamped outside."""
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def _draw(rng: np.random.Generator, opts: dict, name: str, lo: float, hi: float) -> float:
    v = float(rng.uniform(lo, hi))  # always draw, so other draws do not depend on which opts are set
    return float(opts.pop(name)) if name in opts else v


def _walk(t: np.ndarray, rng, opts) -> tuple[_Pose, np.ndarray]:
    freq = _draw(rng, opts, "freq", 0.8, 1.0)  # strides (left + right step) per second
    phase = _draw(rng, opts, "phase", 0.0, 2 * math.pi)
    amp = _draw(rng, opts, "amplitude", 0.85, 1.15)
    arm_amp = _draw(rng, opts, "arm_amplitude", 0.85, 1.15)
    stride = _draw(rng, opts, "stride_length", 1.2, 1.45)  # metres per stride
    advance = bool(opts.pop("advance", False))
    heading = float(opts.pop("heading", 0.0))
    p = _Pose(len(t), "arms_down")
    ph = 2 * math.pi * freq * t + phase
    for side in ("L", "R"):
        s = ph if side == "L" else ph + math.pi
        hip = amp * math.radians(24) * np.sin(s) + math.radians(3)  # forward flexion, > 0 forward
        knee = math.radians(6) + amp * math.radians(55) * ((1 + np.cos(s)) / 2) ** 2
        ankle = amp * math.radians(10) * np.sin(s - 0.6)
        p.about(f"upperleg01.{side}", _X, -hip)
        p.about(f"lowerleg01.{side}", _X, knee)
        p.about(f"foot.{side}", _X, -ankle)
        swing = -arm_amp * math.radians(18) * np.sin(s)  # counter-swing: arm forward with the other leg
        p.about(f"upperarm01.{side}", _X, -swing)
        elbow = math.radians(12) + arm_amp * math.radians(12) * (1 + np.sin(s + math.pi)) / 2
        p.about(f"lowerarm01.{side}", _X, -elbow)
    # Lateral roll with the weight shift, then pelvis yaw with the forward leg, then the heading.
    p.about("root", _Z, amp * math.radians(2.5) * np.cos(ph))
    p.about("root", _Y, np.full(len(t), heading) + amp * math.radians(5) * np.sin(ph))
    p.about("spine03", _Y, -amp * math.radians(7) * np.sin(ph))
    p.about("spine05", _X, np.full(len(t), math.radians(3)))
    p.about("head", _Y, amp * math.radians(3) * np.sin(ph))
    trans = np.zeros((len(t), 3))
    trans[:, 1] = amp * 0.018 * np.cos(2 * ph)  # highest when the legs pass each other
    trans[:, 0] = amp * 0.015 * np.cos(ph)
    if advance:
        d = stride * freq * t
        trans[:, 0] += d * math.sin(heading)
        trans[:, 2] += d * math.cos(heading)
    return p, trans


def _breathing(p: _Pose, t: np.ndarray, rng, opts, amp: float) -> np.ndarray:
    """Breathing, sway and small head motion shared by idle and turn; returns (T, 3) trans."""
    br = _draw(rng, opts, "breath_rate", 0.2, 0.3)  # breaths per second
    sway = _draw(rng, opts, "sway_rate", 0.08, 0.16)
    ph = rng.uniform(0, 2 * math.pi, size=4)
    breath = np.sin(2 * math.pi * br * t + ph[0])
    for bone, a in (("spine03", 1.2), ("spine02", 1.0), ("spine01", 0.8)):
        p.about(bone, _X, -amp * math.radians(a) * breath)  # chest lifts backward on inhale
    p.about("root", _Z, amp * math.radians(1.5) * np.sin(2 * math.pi * sway * t + ph[1]))
    p.about("neck02", _Y, amp * math.radians(5) * np.sin(2 * math.pi * 0.6 * sway * t + ph[2]))
    p.about("head", _X, amp * math.radians(3) * np.sin(2 * math.pi * 0.9 * sway * t + ph[3]))
    trans = np.zeros((len(t), 3))
    trans[:, 0] = amp * 0.012 * np.sin(2 * math.pi * sway * t + ph[1])
    trans[:, 1] = amp * 0.002 * breath
    return trans


def _idle(t, rng, opts):
    amp = _draw(rng, opts, "amplitude", 0.85, 1.15)
    p = _Pose(len(t), "arms_down")
    arm = rng.uniform(0, 2 * math.pi)
    for side in ("L", "R"):
        p.about(f"upperarm01.{side}", _X, amp * math.radians(2) * np.sin(2 * math.pi * 0.15 * t + arm))
    return p, _breathing(p, t, rng, opts, amp)


def _turn(t, rng, opts):
    amp = _draw(rng, opts, "amplitude", 0.85, 1.15)
    sign = 1.0 if rng.uniform() < 0.5 else -1.0
    given = "angle" in opts
    angle = _draw(rng, opts, "angle", 0.5 * math.pi, 2 * math.pi)
    angle = angle if given else sign * angle
    duration = float(opts.pop("duration", t[-1] if len(t) > 1 else 1.0))
    p = _Pose(len(t), "arms_down")
    trans = _breathing(p, t, rng, opts, amp)
    p.about("root", _Y, angle * _smoothstep(t / max(duration, 1e-9)))  # last: turns the swaying body
    return p, trans


def _arm_raise(t, rng, opts):
    amp = _draw(rng, opts, "amplitude", 0.85, 1.15)
    side = opts.pop("side", ("left", "right", "both")[int(rng.integers(3))])
    if side not in ("left", "right", "both"):
        raise InputError(f"arm_raise: side: expected 'left', 'right' or 'both', got {side!r}")
    height = _draw(rng, opts, "height", math.radians(110), math.radians(150))
    period = _draw(rng, opts, "period", 2.5, 4.0)  # seconds for one raise and lowering, repeated
    if period <= 0:
        raise InputError(f"arm_raise: period: expected > 0 s, got {period}")
    p = _Pose(len(t), "arms_down")
    lift = height * (1 - np.cos(2 * math.pi * t / period)) / 2
    for s, sgn in (("L", 1.0), ("R", -1.0)):
        if side == "both" or side[0].upper() == s:
            p.about(f"upperarm01.{s}", _Z, sgn * lift)
    trans = _breathing(p, t, rng, opts, amp * 0.5)
    return p, trans


_KINDS = {"walk": _walk, "turn": _turn, "idle": _idle, "arm_raise": _arm_raise}


def make_motion(kind: str, n_frames: int, fps: float = 30.0, seed: int = 0, **opts) -> dict:
    """A procedural motion clip for :class:`relightnet.body.AnnyBody`.

    Args:
        kind: ``"walk"`` (in place unless ``advance=True``; opts ``freq`` strides/s,
            ``phase``, ``amplitude``, ``arm_amplitude``, ``stride_length`` m, ``heading`` rad),
            ``"turn"`` (in place about +y; ``angle`` rad, signed, eased in and out over
            ``duration`` s, default the clip),
            ``"idle"`` (breathing, sway, head motion; ``breath_rate``, ``sway_rate``, ``amplitude``),
            ``"arm_raise"`` (sideways raise and back every ``period`` s, 2.5–4 by default;
            ``side`` left/right/both, ``height`` rad).
        n_frames: T ≥ 1.
        fps: frames per second.
        seed: draws the unset options.

    Returns:
        ``{"pose": {bone: (T, 3) float32}, "trans": (T, 3) float32}`` — pass it as
        ``AnnyBody()(motion)``; frame i is at time i / fps. With the default ``ground="rest"``
        an in-place walk's lowest point moves within about ±3 cm of y = 0;
        ``AnnyBody(ground="frame")`` keeps a foot on the floor in every frame instead.
    """
    if kind not in _KINDS:
        raise InputError(f"motion kind: expected one of {list(MOTION_KINDS)}, got {kind!r}")
    if int(n_frames) < 1 or fps <= 0:
        raise InputError(f"make_motion: need n_frames >= 1 and fps > 0, got {n_frames}, {fps}")
    rng = np.random.default_rng(seed)
    opts = dict(opts)
    t = np.arange(int(n_frames), dtype=np.float64) / float(fps)
    pose, trans = _KINDS[kind](t, rng, opts)
    if opts:
        raise InputError(f"make_motion({kind!r}): unknown option(s) {sorted(opts)}")
    return {"pose": pose.tensors(), "trans": torch.as_tensor(trans, dtype=torch.float32)}
