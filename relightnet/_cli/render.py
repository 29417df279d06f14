"""``relightnet render`` (any mesh file) and ``relightnet render-body`` (Anny / SMPL, image or video)."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from ..names import OUTFITS
from .argtypes import exposure_arg, nonneg_int, pos_int
from .inputs import load_single_light
from .options import LIGHT_HELP, add_body_args, add_command
from .paths import in_path, out_dir, out_file

logger = logging.getLogger("relightnet.render")

_VIDEO = (".mp4", ".mkv")


def _exposed(img, alpha, exposure):
    """Apply a fixed or automatic exposure (chosen on covered pixels)."""
    from ..light.visualize import auto_exposure

    scale = auto_exposure(img, alpha > 0) if exposure == "auto" else exposure
    return img * scale, scale


def _save_maps(folder: Path, r, transport_v=None, stem: str = "") -> None:
    """Write the maps a person (and the data generator's tests) can inspect."""
    import numpy as np

    from ..io import atomic_write, write_image

    folder.mkdir(parents=True, exist_ok=True)
    with atomic_write(folder / f"{stem}maps.npz") as f:
        np.savez_compressed(
            f, transport=r.transport[0].numpy(), albedo=r.albedo[0].numpy(), shading=r.shading[0].numpy(),
            normals=r.normals[0].numpy(), depth=r.depth[0].numpy(), mask=r.alpha[0].numpy(),
            **({} if transport_v is None else {"vertex_transport": transport_v.numpy()}),
        )
    write_image(folder / f"{stem}albedo.png", r.albedo[0])
    write_image(folder / f"{stem}normals.png", (r.normals[0] * 0.5 + 0.5) * r.alpha[0][..., None], srgb=False)
    s = r.shading[0]
    write_image(folder / f"{stem}shading.png", s / max(float(s.amax()), 1e-8))
    write_image(folder / f"{stem}mask.png", r.alpha[0][..., None].expand(-1, -1, 3), srgb=False)


def run_render(args: argparse.Namespace) -> int:
    from ..io import write_image
    from ..prt import PrtSettings
    from ..render.jobs import render_mesh_file

    out = out_file(args.out, suffixes=(".png",))
    maps = out_dir(args.save_maps, "--save-maps") if args.save_maps else None
    light = load_single_light(args.light, lmax=args.lmax)
    prt = PrtSettings(n_dirs=args.n_dirs, occlusion=args.occlusion, bounces=args.bounces)
    r = render_mesh_file(args.mesh, light, size=args.res, prt=prt)
    img, scale = _exposed(r.image[0], r.alpha[0], args.exposure)
    write_image(out, img)
    if maps is not None:
        _save_maps(maps, r)
    logger.info("wrote %s (exposure x%.3g)", out, scale)
    return 0


def _body_and_params(args):
    """Build the body model and its per-frame parameters from the arguments."""
    from ..body import AnnyBody
    from ..pipeline.scene import load_body, motion_params

    body = load_body(args.body)
    if args.motion:
        params, _ = motion_params(args.motion, body, args.frames, fps=args.fps, seed=args.seed)
    else:
        params = {"pose": body.pose(args.pose)} if isinstance(body, AnnyBody) else {}
    if isinstance(body, AnnyBody):
        params["phenotype"] = dict(args.phenotype or [])
    return body, params


def _albedo(body):
    import torch

    from ..body import AnnyBody, default_albedo

    if isinstance(body, AnnyBody):
        from ..pipeline.smooth_albedo import smooth_default_albedo

        return smooth_default_albedo(body), default_albedo(body, texture_size=None).vertex
    v = torch.full((body.num_verts, 3), 0.6)
    return v, v


def _body_outputs(args) -> tuple[Path, Path | None, Path | None]:
    """(--out, --mask-out, --save-maps) by the output rule: videos for a motion (a mask video
    beside the video), else an image (a mask image beside it)."""
    out = out_file(args.out, suffixes=(".png", *_VIDEO))
    video = out.suffix.lower() in _VIDEO
    if args.motion and not video:
        from ..checks import InputError

        raise InputError(f"--out {out}: a motion renders a video; expected a suffix in {', '.join(_VIDEO)}")
    mask = out_file(args.mask_out, "--mask-out", _VIDEO if video else None) if args.mask_out else None
    if mask is not None and not video and mask.suffix.lower() in _VIDEO:
        from ..checks import InputError

        raise InputError(f"--mask-out {mask}: a still image's mask is an image; expected e.g. mask.png")
    return out, mask, out_dir(args.save_maps, "--save-maps") if args.save_maps else None


def run_render_body(args: argparse.Namespace) -> int:
    from ..io import VideoWriter, write_image
    from ..light import load_light
    from ..prt import PrtSettings
    from ..render.jobs import render_body_frames
    from ..sh.io import check_light_physics

    out, mask_out, maps = _body_outputs(args)
    is_video = out.suffix.lower() in _VIDEO
    light = check_light_physics(load_light(args.light, lmax=args.lmax), args.light)
    body, params = _body_and_params(args)
    albedo, vertex_albedo = _albedo(body)
    if args.outfit and args.avatar:
        from ..checks import InputError

        raise InputError("--avatar brings its own geometry and texture: drop --outfit")
    if args.outfit:
        from ..pipeline.outfits import dressed_body

        body = dressed_body(body, args.outfit)
        albedo, vertex_albedo = body.albedo, None
    if args.avatar:
        from ..pipeline.outfits import captured_body

        body = captured_body(body, in_path(args.avatar, "--avatar", "an avatar file from `relightnet capture`"))
        albedo, vertex_albedo = body.albedo, None
    prt = PrtSettings(n_dirs=args.n_dirs, occlusion=args.occlusion, bounces=args.bounces, seed=args.seed)
    frames = render_body_frames(body, params, light, albedo, camera=args.res, prt=prt, maps=maps is not None,
                                vertex_albedo=vertex_albedo)
    from tqdm import tqdm

    scale = None
    writers = [VideoWriter(p, fps=args.fps, srgb=s) for p, s in ((out, True), (mask_out, False))
               if is_video and p is not None]
    try:
        for fr in tqdm(frames, desc="render-body", unit="frame", disable=not is_video or args.quiet):
            r = fr.render
            if scale is None:  # one exposure for the whole clip: no flicker
                _, scale = _exposed(r.image[0], r.alpha[0], args.exposure)
            pictures = (r.image[0] * scale, r.alpha[0][..., None].expand(-1, -1, 3))
            if writers:
                for w, pic in zip(writers, pictures, strict=False):
                    w.write(pic)
            else:
                write_image(out, pictures[0])
                if mask_out is not None:
                    write_image(mask_out, pictures[1], srgb=False)
            if maps is not None:
                _save_maps(maps, r, fr.transport, stem=f"{fr.index:05d}_" if is_video else "")
    except BaseException:
        for w in writers:
            w.abort()
        raise
    for w in writers:
        w.close()
    logger.info("wrote %s%s (exposure x%.3g)", out, f" and {mask_out}" if mask_out else "", scale)
    return 0


def _prt_options(p: argparse.ArgumentParser, n_dirs: int) -> None:
    p.add_argument("--light", required=True, help=LIGHT_HELP)
    p.add_argument("--lmax", type=nonneg_int, default=2, help="SH order of the light (default: %(default)s)")
    p.add_argument("--res", type=pos_int, default=512, help="square image size in pixels (default: %(default)s)")
    p.add_argument("--occlusion", action=argparse.BooleanOptionalAction, default=True,
                   help="ray-cast visibility in the transport (default: on)")
    p.add_argument("--bounces", type=nonneg_int, default=0, help="interreflection bounces (default: %(default)s)")
    p.add_argument("--n-dirs", type=pos_int, default=n_dirs, help=f"PRT directions (default: {n_dirs})")
    p.add_argument("--exposure", type=exposure_arg, default="auto",
                   help="'auto' (99th percentile of the body at 0.9) or a linear multiplier")
    p.add_argument("--seed", type=int, default=0, help="seed of the PRT direction set and motions")


def register(sub) -> None:
    p = add_command(sub, "render", "Render any mesh file (OBJ/PLY/GLB/...) under an SH light with PRT shading.",
                    "  relightnet render teapot.obj --light studio --out teapot.png\n"
                    "  relightnet render bunny.ply --light sky.exr --res 256 --no-occlusion --out flat.png\n"
                    "  relightnet render room.glb --light sunset --bounces 1 --out gi.png --save-maps maps/\n")
    p.add_argument("mesh", help="mesh file trimesh can read (assumed y-up)")
    p.add_argument("--out", required=True, help="output PNG (8-bit sRGB)")
    p.add_argument("--save-maps", metavar="DIR", help="also write transport/albedo/normal/depth maps here")
    _prt_options(p, 256)
    p.set_defaults(func=run_render)

    p = add_command(sub, "render-body", "Render the Anny body (or an SMPL model file) lit by an SH light with PRT.",
                    "  relightnet render-body --pose arms_crossed --light sunset --res 512 --out body.png\n"
                    "  relightnet render-body --phenotype gender=0 --phenotype weight=0.8 --light studio "
                    "--out b.png --mask-out m.png --save-maps maps/\n"
                    "  relightnet render-body --motion walk --frames 60 --light courtyard --res 256 --out walk.mp4\n"
                    "  relightnet render-body --outfit dress --pose apose --light studio --res 512 --out dressed.png\n"
                    "  relightnet render-body --body smpl:SMPL_NEUTRAL.npz --motion clip.npz "
                    "--light city --out c.mp4\n")
    add_body_args(p)
    p.add_argument("--out", required=True, help="output PNG, or .mp4/.mkv when --motion is given")
    p.add_argument("--mask-out", help="also write the coverage mask: a PNG for a still pose, a mask video "
                   "(.mkv lossless, .mp4) with --motion")
    p.add_argument("--save-maps", metavar="DIR", help="also write transport/albedo/normal/depth maps here")
    p.add_argument("--avatar", metavar="FILE.avatar.npz",
                   help="render a person captured by `relightnet capture` (their shape, offsets and texture)")
    p.add_argument("--outfit", metavar="NAME|random:SEED",
                   help=f"dress Anny in clothes and hair as geometry: {', '.join(OUTFITS)}, or random:SEED")
    _prt_options(p, 64)
    p.set_defaults(func=run_render_body)
