"""The core of the generator: draw every axis, place, frame, compute PRT, render (one still or a clip).

See :mod:`relightnet.data.generate` for the public functions and what the arrays hold.
:func:`clip_geometry` gives the geometry part alone (mesh per frame, crop camera, albedo texture):
the 3D path of ``relightnet compare`` renders the same subject with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from ..checks import InputError
from ..color import luminance
from ..io.image import to_uint8
from ..raster import antialias, interpolate, rasterize
from ..raster.antialias import silhouette_pixels
from ..render.frame import TexturedAlbedo, render_mesh
from ..render.shading import composite
from ..sh import world_to_light
from ..sh.frames import rotation_world_to_light
from ..sh.rotation import rotation_about_up
from .backgrounds import envmap_background, procedural_background
from .clothed import hidden_body_share
from .config import SynthConfig, sample_seed
from .framing import BASE_INTRINSICS, base_camera, camera_intrinsics, crop_camera, draw_view, place_in_camera
from .lights import LightDraw, light_at, sample_light
from .person import PersonStage, group_seed, person_stage, person_transport, seen_vertices, transport_to_camera
from .poses import sample_yaw
from .sample import GENERATOR_VERSION, Sample, SynthAssets, assets_for

__all__ = ["CLIP_KEY", "STREAMS", "ClipGeometry", "clip_geometry", "render_clip", "render_group"]

#: Random streams, one child of the sample's seed sequence each (in this order). A still draws
#: body, pose, albedo, garments and prt from its group's sequence (:mod:`relightnet.data.person`).
STREAMS = ("body", "pose", "view", "albedo", "light", "background", "prt", "noise", "garments")
#: Clips draw from child ``CLIP_KEY`` of the sample's seed sequence.
CLIP_KEY = 100
_SWITCH_PROB = 0.3


def _streams(ss: np.random.SeedSequence) -> dict[str, np.random.Generator]:
    kids = np.random.SeedSequence(ss.entropy, spawn_key=ss.spawn_key).spawn(len(STREAMS))
    return {n: np.random.default_rng(k) for n, k in zip(STREAMS, kids, strict=True)}


def _light_to_env(draw: LightDraw, angle: float, tilt: torch.Tensor) -> torch.Tensor:
    """Q with L(ω) = base(Q ω): mirror · R_upᵀ · tiltᵀ."""
    M = torch.diag(torch.tensor([1.0, -1.0 if draw.mirror else 1.0, 1.0], dtype=torch.float64))
    return M @ rotation_about_up(angle, dtype=torch.float64).T @ tilt.double().T


def _light_schedule(rng, cfg: SynthConfig, split: str, n: int | None) -> tuple[list, list, list]:
    """Draws and per-frame (draw index, angle, level) for a still (n None) or a clip of n frames."""
    a = sample_light(rng, cfg.hdris(split), cfg.lmax, cfg.synthetic_light_prob, cfg.light_mix)
    if n is None:
        return [a], [(0, a.angle, a.level)], []
    b = sample_light(rng, cfg.hdris(split), cfg.lmax, cfg.synthetic_light_prob, cfg.light_mix)
    rates = [(0.0 if rng.uniform() < 0.25 else math.radians(rng.uniform(-60, 60)), rng.uniform(-0.4, 0.4))
             for _ in range(2)]
    switch = int(rng.integers(1, n)) if n > 1 and rng.uniform() < _SWITCH_PROB else None
    if cfg.clip_lights != "random":  # evaluation clips: a fixed light, with one switch half-way or none
        rates = [(0.0, 0.0), (0.0, 0.0)]
        switch = n // 2 if cfg.clip_lights == "switch" and n > 1 else None
    frames = []
    for t in range(n):
        i = 0 if switch is None or t < switch else 1
        dt = (t - (0 if i == 0 else switch)) / 30.0
        d = (a, b)[i]
        frames.append((i, d.angle + rates[i][0] * dt, d.level * math.exp(rates[i][1] * dt)))
    draws = [a, b] if switch is not None else [a]
    return draws, frames, ([switch] if switch is not None else [])


def _light_meta(d: LightDraw) -> dict:
    return {**d.info, "rotation_deg": math.degrees(d.angle), "mirror": d.mirror, "level": d.level}


def _background(rng, cfg, split, assets: SynthAssets, draw: LightDraw, angle, tilt, intr, subject: float):
    use_light_env = draw.source == "hdri" and rng.uniform() < 0.6
    use_env = rng.uniform() < 0.3
    hdris = cfg.hdris(split)
    name = hdris[int(rng.integers(len(hdris)))]
    r_angle, r_mirror = float(rng.uniform(0, 2 * math.pi)), bool(rng.uniform() < 0.5)
    blur = float(rng.uniform(0.002, 0.02) * cfg.res)
    factor = float(math.exp(rng.uniform(math.log(0.35), math.log(2.5))))
    sub = np.random.default_rng(int(rng.integers(2**31 - 1)))
    if use_light_env:
        gains = torch.tensor(draw.info["white_balance"], dtype=torch.float32)
        gain = math.pi * draw.info["scale"] * draw.level * gains
        img = envmap_background(assets.envmap(draw.hdri), intr, cfg.res, _light_to_env(draw, angle, tilt),
                                gain, blur)
        return img, {"kind": "envmap", "hdri": draw.hdri, "matches_light": True, "blur_px": blur}
    if use_env:
        q = torch.diag(torch.tensor([1.0, -1.0 if r_mirror else 1.0, 1.0], dtype=torch.float64))
        q = q @ rotation_about_up(r_angle, dtype=torch.float64).T
        img = envmap_background(assets.envmap(name), intr, cfg.res, q, 1.0, blur)
        mean = float(luminance(img).mean())
        img = img * (factor * subject / max(mean, 1e-6))
        return img, {"kind": "envmap", "hdri": name, "matches_light": False, "rotation_deg": math.degrees(r_angle),
                     "mirror": r_mirror, "blur_px": blur, "level": factor * subject}
    return procedural_background(sub, cfg.res, factor * subject)


@dataclass(frozen=True, eq=False)
class ClipGeometry:
    """The geometry of a still or clip: the posed, placed mesh, its crop camera and its albedo texture.

    Everything is in the camera frame of the sample (the crop camera has rotation I, so its
    light frame is the sample's light frame, see :mod:`relightnet.data.generate`).

    Attributes:
        verts: (T, V, 3) float32 vertex positions per frame (T = 1 for a still).
        normals: (T, V, 3) float32 unit vertex normals per frame.
        faces: (F, 3) int64 triangles.
        camera: the crop :class:`~relightnet.raster.Camera` (batch 1, size ``(res, res)``).
        albedo: the :class:`~relightnet.render.TexturedAlbedo` (texture (S, S, 3) linear RGB).
        box: the :class:`~relightnet.data.framing.CropBox` in base-camera pixels.
        pitch: camera pitch (radians); ``R``: (3, 3) float64 the pitch rotation.
        world_to_camera: (4, 4) float64, the world (before yaw) → camera transform.
        phenotype, pose, yaw, view, outfit, garments: what was drawn (pose: the pose description).
        regions: (V, R) the smoothed clothing-region field of the outfit (garment vertices one-hot).
        covered: (F,) bool body faces hidden under garments; n_body_faces: the body's face count
            (the body's faces come first, then the garments').
        midpoints: (M, 3) int64 (vertex, endpoint a, endpoint b) of the garments' subdivided outer
            sides' midpoints (their PRT: :func:`relightnet.prt.refined_transport`).
    """

    verts: torch.Tensor
    normals: torch.Tensor
    faces: torch.Tensor
    camera: object
    albedo: TexturedAlbedo
    box: object
    pitch: float
    R: torch.Tensor
    world_to_camera: torch.Tensor
    phenotype: dict
    pose: dict
    yaw: float
    view: dict
    outfit: dict
    regions: np.ndarray
    garments: dict
    covered: torch.Tensor
    n_body_faces: int
    midpoints: torch.Tensor


def _geometry(cfg: SynthConfig, person: PersonStage, rv: np.random.Generator) -> ClipGeometry:
    """Draw the view stream (yaw, then the camera) and place the person in front of the camera."""
    m = person.mesh
    yaw = sample_yaw(rv)
    view = draw_view(rv, cfg.partial_crop_prob)
    v_cam, n_cam, R, pitch, w2c = place_in_camera(m.verts, m.normals, person.joints, view, yaw)
    cam, box = crop_camera(v_cam.reshape(-1, 3), base_camera(), cfg.res, cfg.pad, cfg.jitter, rv, view["mode"])
    return ClipGeometry(verts=v_cam, normals=n_cam, faces=m.faces, camera=cam,
                        albedo=TexturedAlbedo(m.tex, m.uv, m.uv_faces), box=box, pitch=pitch, R=R,
                        world_to_camera=w2c, phenotype=person.phenotype, pose=person.pose, yaw=yaw, view=view,
                        outfit=person.outfit, regions=m.field, garments=person.garments, covered=m.covered,
                        n_body_faces=m.n_body_faces, midpoints=m.midpoints)


def _person_streams(cfg: SynthConfig, split: str, index: int, ss, n_frames: int | None) -> dict:
    """The streams the person stage draws from: the group's (stills) or the clip's own."""
    return _streams(ss if n_frames is not None else group_seed(cfg, split, index)[0])


def clip_geometry(cfg: SynthConfig, split: str, index: int, n_frames: int | None, body=None) -> ClipGeometry:
    """The geometry of still (``n_frames`` None) or clip ``index`` of ``split``, without rendering it.

    It draws from the same random streams as :func:`~relightnet.data.generate_sample` /
    :func:`~relightnet.data.generate_sequence` (which use it), so the mesh, camera and
    texture are those of the generated sample: rasterizing ``verts`` with ``camera`` gives
    its ``mask`` (bit for bit at the same torch thread count).

    Args:
        cfg, split, index: as :func:`~relightnet.data.generate_sequence`.
        n_frames: T ≥ 1 for a clip, None for a still (then T = 1 in the result).
        body: None, an :class:`~relightnet.body.AnnyBody`, or ``SynthAssets`` (fastest).

    Returns:
        :class:`ClipGeometry` with (T, V, 3) vertices and normals.
    """
    ss = sample_seed(cfg, split, index)
    if n_frames is not None:
        if isinstance(n_frames, bool) or not isinstance(n_frames, int | np.integer) or n_frames < 1:
            raise InputError(f"n_frames: expected None or an integer >= 1, got {n_frames!r}")
        ss = np.random.SeedSequence(ss.entropy, spawn_key=(CLIP_KEY,))
        n_frames = int(n_frames)
    assets = assets_for(body)
    person = person_stage(cfg, _person_streams(cfg, split, int(index), ss, n_frames), assets,
                          1 if n_frames is None else n_frames)
    return _geometry(cfg, person, _streams(ss)["view"])


def _render_frames(cfg: SynthConfig, geo: ClipGeometry, person: PersonStage, draws, frames, tilt, frs):
    """Stage render: the person's PRT turned into the camera's light frame and the maps of every
    frame (fragments ``frs``, :func:`_view_stage`) under its light → (per-field lists, body-through-cloth
    shares) for the composite stage."""
    faces, cam, talb = geo.faces, geo.camera, geo.albedo
    field = torch.as_tensor(geo.regions)
    Q = geo.world_to_camera[:3, :3]
    keys = ("image", "mask", "albedo", "transport", "transport_unoccluded", "light", "normals", "depth", "parts")
    acc = {k: [] for k in keys}
    through = []
    for t in range(len(frames)):
        i, angle, level = frames[t]
        light = light_at(draws[i], angle, level, tilt)
        v, n, fr = geo.verts[t], geo.normals[t], frs[t]
        Tv, Tu = transport_to_camera(torch.stack([person.transport[t], person.transport_unoccluded[t]]), Q, cfg.lmax)
        rend = render_mesh(v, faces, Tv, talb, light, cam, normals=n, maps=True, frags=fr)
        through.append(hidden_body_share(fr.pix_face, geo.covered, geo.n_body_faces))
        reg = torch.einsum("nk,nkr->nr", fr.pix_bary.float(), field[faces[fr.pix_face]]).argmax(1)
        parts = torch.zeros(cfg.res * cfg.res, dtype=torch.uint8)
        parts.index_copy_(0, fr.pix, (reg + 1).to(torch.uint8))
        for k, x in (("image", rend.image[0]), ("mask", rend.alpha[0]), ("albedo", rend.albedo[0]),
                     ("transport", rend.transport[0]), ("transport_unoccluded", interpolate(Tu, fr, faces)[0]),
                     ("light", light), ("normals", world_to_light(rend.normals[0])),
                     ("depth", torch.nan_to_num(rend.depth[0], posinf=0.0)), ("parts", parts.view(cfg.res, cfg.res))):
            acc[k].append(x)
    return acc, through


def _composite_frames(cfg: SynthConfig, noise_rng, acc: dict, bg: torch.Tensor, frs, clips, faces):
    """Stage composite: each frame over the background (:func:`relightnet.render.composite`), its
    silhouette antialiased, sensor noise added → (8-bit person frames, 8-bit composites); the noise
    goes into ``acc["image"]`` too."""
    sigma = float(cfg.noise_std)
    srgb, comp = [], []
    for t in range(len(frs)):
        mask = acc["mask"][t][..., None]
        lin = composite(acc["image"][t][None], mask[None], bg)[0]
        aa = antialias(lin[None], frs[t], clips[t], faces)[0]
        lin = torch.where(silhouette_pixels(mask[..., 0] > 0)[..., None], aa, lin)
        if sigma > 0:
            noise = torch.from_numpy(noise_rng.normal(0.0, sigma, (cfg.res, cfg.res, 3)).astype(np.float32))
            acc["image"][t] = acc["image"][t] + noise * mask
            lin = lin + noise
        srgb.append(to_uint8(acc["image"][t]))
        comp.append(to_uint8(lin))
    return srgb, comp


def _clip_meta(cfg: SynthConfig, split: str, index: int, geo: ClipGeometry, draws, frames, switches, bg_desc,
               person: PersonStage, through: list, n_frames: int | None) -> dict:
    """Stage write: the sample's JSON metadata (what was drawn)."""
    outfit, view, box, pitch = geo.outfit, geo.view, geo.box, geo.pitch
    bounce, dir_seed = person.bounce, person.dir_seed
    _, group, member = group_seed(cfg, split, index)
    reuse = {"group": group, "member": member, "size": cfg.prt_reuse} if n_frames is None else None
    intr = camera_intrinsics(geo.camera)
    meta = {
        "generator_version": GENERATOR_VERSION,
        "kind": "still" if n_frames is None else "sequence",
        "seed": {"seed": cfg.seed, "split": split, "index": index},
        "phenotype": geo.phenotype,
        "pose": {**geo.pose, "yaw_deg": math.degrees(geo.yaw)},
        "outfit": {"skin_tone": outfit["skin_tone"], "hair": outfit["hair"] is not None, "sleeves": outfit["sleeves"],
                   "legs": outfit["legs"], **{g: outfit[g]["pattern"] for g in ("top", "bottom", "shoes")}},
        "camera": {"intrinsics": list(intr), "res": cfg.res, "view": torch.eye(4).tolist(),
                   "world_to_camera": geo.world_to_camera.tolist(), "pitch_deg": math.degrees(pitch),
                   "distance": view["distance"], "height": view["height"], "lateral": view["lateral"],
                   "crop_box": box.as_list(), "crop_mode": box.mode, "base_intrinsics": list(BASE_INTRINSICS)},
        "light": {**_light_meta(draws[0]), "tilt_deg": math.degrees(pitch)},
        "background": bg_desc,
        "flags": {"bounce": bounce, "noise_std": float(cfg.noise_std)},
        "prt": {"lmax": cfg.lmax, "n_dirs": cfg.n_dirs, "direction_seed": dir_seed, "reuse": reuse},
        "garments": {**geo.garments, "hidden_body_share": through if n_frames is not None else through[0]},
    }
    if n_frames is not None:
        meta["lights"] = [_light_meta(d) for d in draws]
        meta["frames"] = [{"light": i, "rotation_deg": math.degrees(a), "level": lv} for i, a, lv in frames]
        meta["switch_frames"] = switches
        meta["n_frames"] = n_frames
        meta["fps"] = 30.0
    return meta


@dataclass(frozen=True, eq=False)
class _View:
    """A sample's streams after its view was drawn, its geometry and every frame's clip-space vertices and
    fragments (what its PRT must cover: :func:`~relightnet.data.person.seen_vertices`)."""

    streams: dict
    geo: ClipGeometry
    clips: list
    frags: list


def _view_stage(cfg: SynthConfig, person: PersonStage, ss: np.random.SeedSequence) -> _View:
    """Draw the view (the sample's ``view`` stream), place the person and rasterize every frame."""
    r = _streams(ss)
    geo = _geometry(cfg, person, r["view"])
    clips = [geo.camera.transform(geo.verts[t]) for t in range(geo.verts.shape[0])]
    return _View(r, geo, clips, [rasterize(c, geo.faces, geo.camera.size) for c in clips])


def _seen(person: PersonStage, views: list[_View]) -> torch.Tensor:
    """(T, V') the vertices some frame of ``views`` shows, per frame."""
    m = person.mesh
    return torch.stack([seen_vertices(m.faces, m.verts.shape[1], [vw.frags[t] for vw in views])
                        for t in range(m.verts.shape[0])])


def render_clip(cfg: SynthConfig, split: str, index: int, ss: np.random.SeedSequence, assets: SynthAssets,
                n_frames: int | None, person: PersonStage | None = None) -> Sample:
    """Make a still (``n_frames`` None: arrays without a T axis) or a clip of ``n_frames`` frames.

    Stages: the person (body, pose, look, garments: from the group's streams for a still,
    :mod:`relightnet.data.person`) → draw the view (the sample's streams) and rasterize it → the
    person's PRT of the vertices the view shows (pass ``person`` with its transport to reuse it
    across the group; it must cover them) → draw the lights → render every frame's maps →
    composite over the drawn background → the arrays and metadata.
    """
    if person is None:
        T = 1 if n_frames is None else n_frames
        person = person_stage(cfg, _person_streams(cfg, split, index, ss, n_frames), assets, T)
    view = _view_stage(cfg, person, ss)
    if person.transport is None:
        person = person_transport(cfg, person, _seen(person, [view]))
    return _finish(cfg, split, index, assets, n_frames, person, view)


def _finish(cfg: SynthConfig, split: str, index: int, assets: SynthAssets, n_frames: int | None,
            person: PersonStage, view: _View) -> Sample:
    """The stages of :func:`render_clip` after the view and the PRT: lights, maps, composite, arrays."""
    T = 1 if n_frames is None else n_frames
    r, geo = view.streams, view.geo
    draws, frames, switches = _light_schedule(r["light"], cfg, split, n_frames)
    tilt = rotation_world_to_light(geo.R).float()
    acc, through = _render_frames(cfg, geo, person, draws, frames, tilt, view.frags)

    m0 = acc["mask"][0] > 0
    lum0 = luminance(acc["image"][0])
    subject = float(lum0[m0].mean()) if bool(m0.any()) else 0.2
    i0, a0, _ = frames[0]
    bg, bg_desc = _background(r["background"], cfg, split, assets, draws[i0], a0, tilt,
                              camera_intrinsics(geo.camera), subject)
    srgb, comp = _composite_frames(cfg, r["noise"], acc, bg, view.frags, view.clips, geo.faces)

    arrays = {k: torch.stack(v) for k, v in acc.items()}
    arrays["image_srgb"] = torch.stack(srgb)
    arrays["image_composite"] = torch.stack(comp)
    arrays["background"] = bg[None].expand(T, -1, -1, -1)
    out_arrays = {}
    for k, v in arrays.items():
        a = v.detach().cpu().numpy()
        a = a if a.dtype in (np.uint8,) else a.astype(np.float32)
        out_arrays[k] = np.ascontiguousarray(a[0] if n_frames is None else a)
    return Sample(out_arrays, _clip_meta(cfg, split, index, geo, draws, frames, switches, bg_desc, person, through,
                                         n_frames))


def render_group(cfg: SynthConfig, split: str, indices, assets: SynthAssets) -> list[Sample]:
    """Make the stills ``indices`` (ascending), computing each group's person stage and PRT once.

    Each group's views are drawn and rasterized first, so that its PRT casts only the vertices
    one of them shows. Every sample equals :func:`render_clip` of it alone (bit for bit at the
    same thread count).
    """
    groups: dict[int, list[int]] = {}
    for i in indices:
        groups.setdefault(group_seed(cfg, split, int(i))[1], []).append(int(i))
    out = []
    for members in groups.values():
        person = person_stage(cfg, _streams(group_seed(cfg, split, members[0])[0]), assets, 1)
        views = [_view_stage(cfg, person, sample_seed(cfg, split, i)) for i in members]
        person = person_transport(cfg, person, _seen(person, views))
        out += [_finish(cfg, split, i, assets, None, person, vw) for i, vw in zip(members, views, strict=True)]
    return out
