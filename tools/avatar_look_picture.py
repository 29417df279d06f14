"""Draw the README's pictures of the dressed avatar and the replaced person: ``docs/avatar_look.png``, and of
the hems and shoes: ``docs/avatar_hems.png``.

Run: ``.venv/bin/python tools/avatar_look_picture.py [--out docs/avatar_look.png] [--hems docs/avatar_hems.png]``
(ANNY_CACHE_DIR set by make).

Top row: the named outfits (``--outfit NAME``) and ``random:3`` on the walking avatar, PRT-lit by
the ``studio`` preset. Bottom row: the neckline and sleeves of the default albedo, face-wise
(before) and through the smooth field (now), then a generated target (a person walking across a
known background), its clean plate, and ``avatar --replace-person --outfit casual`` on it at three
times (the avatar follows the person across the frame).

The hems picture: close-ups of the jacket's neckline and sleeve end and the casual outfit's trouser
hem, each with the generator's face-wise border (left) and the hem cut along a smooth line (right),
then the feet in the four shoe kinds.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import torch


def _u8(img: torch.Tensor) -> np.ndarray:
    from relightnet.color import linear_to_srgb

    return (linear_to_srgb(img.clamp(0, 1)) * 255).round().to(torch.uint8).numpy()


def _outfits(body, light) -> np.ndarray:
    from relightnet.body import make_motion
    from relightnet.names import OUTFITS
    from relightnet.pipeline.outfits import dressed_body
    from relightnet.prt import PrtSettings
    from relightnet.render import render_body_frames

    cols = []
    for spec in (*OUTFITS, "random:3"):
        d = dressed_body(body, spec)
        fr = list(render_body_frames(d, make_motion("walk", 12), light, d.albedo, camera=(320, 192),
                                     prt=PrtSettings(n_dirs=64), n_frames=12, visible_only=True))[9]
        cols.append(_u8(fr.render.image[0] + 0.93 * (1 - fr.render.alpha[0][..., None])))
    return np.concatenate(cols, 1)


def _closeups(body, light) -> list[np.ndarray]:
    from relightnet.body import default_albedo
    from relightnet.pipeline.smooth_albedo import smooth_default_albedo
    from relightnet.prt import PrtSettings, vertex_transport
    from relightnet.raster import look_at, perspective_camera
    from relightnet.render import TexturedAlbedo, render_mesh

    out = body({"pose": body.pose("apose")})
    cam = perspective_camera(look_at(torch.tensor([0.0, 1.3, 0.95]), torch.tensor([0.0, 1.3, 0.0])), (320, 320),
                             fov_deg=35)
    T = vertex_transport(out.verts[0], out.faces, out.normals[0], lmax=2, prt=PrtSettings(n_dirs=64),
                         manifold="ignore")
    old = default_albedo(body)
    panels = []
    for alb in (TexturedAlbedo(old.texture, body.uv, body.uv_faces), smooth_default_albedo(body)):
        r = render_mesh(out.verts[0], out.faces, T, alb, light, cam)
        panels.append(_u8(r.image[0] + 0.93 * (1 - r.alpha[0][..., None])))
    return panels


def _replaced(body, tmp: Path) -> list[np.ndarray]:
    from relightnet.io import read_image, read_video
    from relightnet.light import preset_light
    from relightnet.pipeline import AvatarLook, AvatarPlacement
    from relightnet.pipeline.avatar import avatar
    from relightnet.pipeline.walk_target import walking_target
    from relightnet.prt import PrtSettings

    wt = walking_target(tmp, size=(320, 320), n_frames=16, suffix=".mp4", body=body)
    avatar(wt.video, tmp / "av.mp4", light=preset_light("studio"), look=AvatarLook(body=body, outfit="casual"),
           placement=AvatarPlacement(replace_person=True), prt=PrtSettings(n_dirs=32), progress=False)
    target = list(read_video(wt.video))[8]
    plate = (read_image(tmp / "av.plate.png") * 255).round().byte().numpy()
    frames = list(read_video(tmp / "av.mp4"))
    return [target, plate, *(frames[t] for t in (4, 8, 12))]


def _hems(body, light) -> np.ndarray:
    from relightnet.pipeline.outfits import DressedBody, draw_outfit
    from relightnet.prt import PrtSettings, vertex_transport
    from relightnet.raster import look_at, perspective_camera
    from relightnet.render import render_mesh

    views = {"jacket": (((0.0, 1.38, 0.55), (0.0, 1.36, 0.0)), ((0.75, 1.05, 0.45), (0.3, 1.0, 0.0))),
             "casual": (((0.25, 0.2, 0.45), (0.1, 0.16, 0.0)),)}
    panels = []
    for name, vs in views.items():
        pair = [DressedBody(body, draw_outfit(name), hems=h) for h in (False, True)]
        for eye, target in vs:
            cam = perspective_camera(look_at(torch.tensor(eye), torch.tensor(target)), (240, 240), fov_deg=35)
            for d in pair:
                out = d()
                T = vertex_transport(out.verts[0], out.faces, out.normals[0], lmax=2, prt=PrtSettings(n_dirs=64),
                                     manifold="ignore")
                r = render_mesh(out.verts[0], out.faces, T, d.albedo, light, cam)
                panels.append(_u8(r.image[0] + 0.93 * (1 - r.alpha[0][..., None])))
    cam = perspective_camera(look_at(torch.tensor([0.55, 0.3, 0.65]), torch.tensor([0.0, 0.1, 0.05])), (240, 240),
                             fov_deg=35)
    for spec in ("casual", "coat", "jacket", "dress"):  # sneaker, boot, dress shoe, flat
        d = DressedBody(body, draw_outfit(spec))
        out = d()
        T = vertex_transport(out.verts[0], out.faces, out.normals[0], lmax=2, prt=PrtSettings(n_dirs=64),
                             manifold="ignore")
        r = render_mesh(out.verts[0], out.faces, T, d.albedo, light, cam)
        panels.append(_u8(r.image[0] + 0.93 * (1 - r.alpha[0][..., None])))
    return np.concatenate(panels, 1)


def main() -> None:
    from relightnet.body import AnnyBody
    from relightnet.io import write_image
    from relightnet.light import preset_light

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/avatar_look.png")
    ap.add_argument("--hems", default="docs/avatar_hems.png")
    args = ap.parse_args()
    body = AnnyBody()
    light = preset_light("studio")
    write_image(args.hems, torch.from_numpy(_hems(body, light)).float() / 255, srgb=False)
    top = _outfits(body, light)
    with tempfile.TemporaryDirectory() as d:
        bottom = np.concatenate([*_closeups(body, light), *_replaced(body, Path(d))], 1)
    w = max(top.shape[1], bottom.shape[1])
    pad = [np.pad(x, ((0, 0), (0, w - x.shape[1]), (0, 0)), constant_values=255) for x in (top, bottom)]
    write_image(args.out, torch.from_numpy(np.concatenate(pad, 0)).float() / 255, srgb=False)


if __name__ == "__main__":
    main()
