"""The avatar's parts from user arguments: body model, motion, albedo and camera.

One place turns ``--body``, ``--motion``, ``--albedo`` and ``--camera`` into objects, with
one-line errors naming the bad input; the avatar job and ``render-body`` share it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from pathlib import Path

import torch

from ..checks import InputError, ShapeError
from ..raster import Camera, look_at, perspective_camera

__all__ = ["load_body", "open_motion", "motion_params", "avatar_albedo", "load_camera"]

_MOTION_FILES = (".npz", ".pkl")


def load_body(spec="anny"):
    """A body model from ``"anny"``, ``"smpl:PATH"`` (a user-supplied SMPL file) or a body model."""
    from ..body import AnnyBody, SMPLBody
    from ..body.base import BodyModel

    if isinstance(spec, BodyModel):
        return spec
    if spec == "anny":
        return AnnyBody()
    if isinstance(spec, str) and spec.startswith("smpl:"):
        return SMPLBody(spec[5:])
    raise InputError(f"body: expected 'anny' or 'smpl:PATH', got {spec!r}")


def open_motion(motion, body, fps: float = 30.0, seed: int = 0) -> Callable[[int], tuple[dict, int]]:
    """Check a motion against its body now (reading a motion file once); frames come later.

    Args:
        motion: a preset name (:data:`relightnet.body.MOTION_KINDS`; Anny only), an Anny motion
            file (.npz from ``relightnet fit``, :mod:`relightnet.body.anny_motion`), an SMPL-style
            motion file (.npz/.pkl: poses (T, 72), betas (10,), trans (T, 3); SMPL bodies only),
            or a mapping of parameters with a frame axis of T.
        body: the body model they drive.
        fps: frame rate presets are made at.

    Returns:
        ``frames(n_frames) -> (params, T)``: a preset is made ``n_frames`` long; a file or a
        mapping has its own T.
    """
    from ..body import MOTION_KINDS, AnnyBody, load_anny_motion, load_motion, make_motion
    from ..body.anny_motion import is_anny_motion

    is_anny = isinstance(body, AnnyBody)
    if isinstance(motion, Mapping):
        fixed = dict(motion), _mapping_frames(motion)
        return lambda n_frames: fixed
    motion = str(motion)
    if Path(motion).suffix.lower() in _MOTION_FILES:
        if is_anny_motion(motion):  # written by `relightnet fit`
            if not is_anny:
                raise InputError(f"--motion {motion}: an Anny motion file (from `relightnet fit`) drives --body anny")
            am = load_anny_motion(motion, body.joint_names)
            fixed = am.body_params(), am.n_frames
            return lambda n_frames: fixed
        if is_anny:
            raise InputError(f"--motion {motion}: SMPL-style motion files drive an SMPL body (--body smpl:MODEL.npz); "
                             f"for Anny use a preset ({', '.join(MOTION_KINDS)}) or a motion from `relightnet fit`")
        m = load_motion(motion)
        fixed = m.body_params(), m.n_frames
        return lambda n_frames: fixed
    if motion not in MOTION_KINDS:
        raise InputError(f"--motion {motion}: expected a preset ({', '.join(MOTION_KINDS)}) or a motion file "
                         f"({'/'.join(_MOTION_FILES)})")
    if not is_anny:
        raise InputError(f"--motion {motion}: presets drive Anny; an SMPL body needs a motion file")
    return lambda n_frames: (make_motion(motion, n_frames, fps=fps, seed=seed), n_frames)


def motion_params(motion, body, n_frames: int, fps: float = 30.0, seed: int = 0) -> tuple[dict, int]:
    """Per-frame body parameters and their frame count: :func:`open_motion` made ``n_frames`` long.

    Returns:
        (params, T).
    """
    return open_motion(motion, body, fps, seed)(n_frames)


def _mapping_frames(params: Mapping) -> int:
    rows = set()

    def walk(p):
        for v in p.values():
            if isinstance(v, Mapping):
                walk(v)
            elif isinstance(v, torch.Tensor) and v.dim() >= 2:
                rows.add(v.shape[0])

    walk(params)
    rows.discard(1)
    if len(rows) > 1:
        raise ShapeError(f"motion: tensors disagree on the frame count: {sorted(rows)}")
    return rows.pop() if rows else 1


def avatar_albedo(body, albedo="default"):
    """The avatar's albedo: a :class:`~relightnet.render.TexturedAlbedo` or a (V, 3) tensor.

    Args:
        body: the body model.
        albedo: ``"default"`` (Anny's plain-coloured outfit with smooth garment boundaries,
            :func:`~relightnet.pipeline.smooth_albedo.smooth_default_albedo`; grey 0.6 for SMPL), a texture
            image path (sRGB, in the body's UV layout), a (V, 3) tensor or a TexturedAlbedo.
    """
    from ..body import AnnyBody
    from ..io.image import read_image
    from ..render.frame import TexturedAlbedo

    if isinstance(albedo, TexturedAlbedo):
        return albedo
    if isinstance(albedo, torch.Tensor):
        if albedo.shape != (body.num_verts, 3):
            raise ShapeError(f"albedo: expected ({body.num_verts}, 3), got {tuple(albedo.shape)}")
        return albedo.float()
    if albedo == "default":
        if isinstance(body, AnnyBody):
            from .smooth_albedo import smooth_default_albedo

            return smooth_default_albedo(body)
        return torch.full((body.num_verts, 3), 0.6)
    path = Path(albedo)
    if not path.is_file():
        raise InputError(f"--albedo {albedo}: texture file not found (or say 'default')")
    tex = read_image(path, linear=True).clamp(0, 1)
    return TexturedAlbedo(tex, body.uv, body.uv_faces)


def load_camera(spec, size) -> Camera:
    """A camera from a JSON file ``{"eye": [x, y, z], "target": [x, y, z], "fov_deg": 35}``
    (world frame, y up; ``up`` optional) at image ``size`` (H, W)."""
    path = Path(spec)
    if not path.is_file():
        raise InputError(f"--camera {spec}: camera file not found")
    try:
        d = json.loads(path.read_text())
        eye = torch.tensor([float(x) for x in d["eye"]])
        target = torch.tensor([float(x) for x in d.get("target", (0.0, 0.85, 0.0))])
        up = torch.tensor([float(x) for x in d.get("up", (0.0, 1.0, 0.0))])
        fov = float(d.get("fov_deg", 35.0))
    except (ValueError, KeyError, TypeError, AttributeError, RecursionError) as e:
        raise InputError(f"--camera {spec}: expected JSON with eye [x,y,z], target [x,y,z], fov_deg ({e})") from None
    if eye.shape != (3,) or target.shape != (3,) or up.shape != (3,) or not 0 < fov < 180 or not math.isfinite(fov):
        raise InputError(f"--camera {spec}: eye/target/up need 3 numbers and fov_deg a value in (0, 180)")
    if not all(bool(torch.isfinite(v).all()) for v in (eye, target, up)):
        raise InputError(f"--camera {spec}: eye, target and up must be finite numbers (no NaN or Infinity)")
    if float((eye - target).norm()) < 1e-6:
        raise InputError(f"--camera {spec}: eye and target coincide")
    return perspective_camera(look_at(eye, target, up), size, fov_deg=fov)
