"""``relightnet relight-image`` and ``relight-video``: the 2D path on photos and videos (pipeline jobs 1, 2)."""

from __future__ import annotations

import argparse
import logging

from ..errors import InputError
from ..names import STREAMING_SMOOTHING, smoothing_help
from .argtypes import pos_float, quality
from .inputs import load_single_light, read_photo
from .options import LIGHT_HELP, add_command, add_mask_source_arg, add_model_args
from .paths import in_path, out_dir, out_file

logger = logging.getLogger("relightnet.relight")


def run(args: argparse.Namespace) -> int:
    from ..io.probe import IMAGE_OUT_SUFFIXES, check_image_file  # torch-free

    out = out_file(args.out, suffixes=IMAGE_OUT_SUFFIXES, inputs=(args.image, args.mask, args.light, args.checkpoint))
    maps = out_dir(args.save_maps, "--save-maps") if args.save_maps else None
    check_image_file(args.image, "an image")  # an oversized or broken photo is refused before torch loads
    light = load_single_light(args.light)  # a bad light fails before the photo is decoded and segmented
    # then: a bad photo fails before the heavy imports (and the person is found in it)
    image, mask, alpha = read_photo(args.image, args.mask, args.mask_source)
    if alpha is not None and out.suffix.lower() in (".jpg", ".jpeg"):
        raise InputError(f"--out {out}: {args.image} is a cut-out (it has alpha) and a JPEG has none; "
                         "write .png or .webp")
    from ..io import write_image
    from ..io.icc import photo_profile
    from ..pipeline.backends import make_predictor
    from ..pipeline.relight_image import relight_image

    model = make_predictor(args.backend, args.checkpoint, args.device)
    # without --save-maps the CNN's maps are never held at the photo's size (memory budget)
    # a cut-out's own alpha is its edge; any other mask gets the soft matte in its border band
    res = relight_image(model, image, light, mask, keep_exposure=not args.absolute, detail=not args.cnn_albedo,
                        maps=maps is not None, soft_edges=alpha is None and not args.hard_edges)
    del image, mask
    if res.mask_predicted:
        logger.info("no --mask: the person was found by the model's mask head")
    relit, kept = res.image, {"prediction": res.prediction, "albedo": res.albedo, "light": res.light}
    del res  # from here each full-size map is freed once written
    # a cut-out stays a cut-out; a Display-P3 photo gives a Display-P3 file (io.icc)
    write_image(out, relit, srgb=False, alpha=alpha, icc=photo_profile(args.image), quality=args.quality)
    del relit
    if maps is not None:
        _save_maps(maps, kept)
    logger.info("wrote %s", out)
    return 0


def _save_maps(d, kept: dict) -> None:
    """``--save-maps``: the full-size maps of a photo (``kept``: its prediction, relit albedo and light
    used, taken out as they are written so that each is freed then)."""
    import numpy as np
    import torch

    from ..io import atomic_write, write_image
    from ..sh import save_light

    d.mkdir(parents=True, exist_ok=True)
    albedo = kept.pop("albedo")
    write_image(d / "albedo.png", albedo.permute(1, 2, 0))
    del albedo
    p, used = kept.pop("prediction"), kept.pop("light")
    s = p.shading()[0].mul_(p.mask[0]).permute(1, 2, 0)
    write_image(d / "shading.png", s.div_(s.amax().clamp_min(1e-8)))
    del s
    write_image(d / "mask.png", p.mask[0].permute(1, 2, 0).expand(-1, -1, 3), srgb=False)
    with atomic_write(d / "transport.npz") as f:
        np.savez_compressed(f, transport=p.transport[0].numpy(), mask=p.mask[0, 0].numpy())
    save_light(d / "light_estimated.npz", p.light[0])
    save_light(d / "light_used.npz", used.to(torch.float32))


def run_video(args: argparse.Namespace) -> int:
    from ..pipeline.backends import make_predictor
    from ..pipeline.relight_video import relight_video
    from ..pipeline.settings import VideoLightSettings

    out = out_file(args.out, suffixes=(".mp4", ".mkv"), inputs=(args.video, args.masks, args.light, args.checkpoint))
    in_path(args.video, "VIDEO", "a video file")
    if args.masks:
        in_path(args.masks, "--masks", "a folder of mask images or a mask video")
    light = load_single_light(args.light)
    model = make_predictor(args.backend, args.checkpoint, args.device)
    lights = VideoLightSettings(smoothing=args.smoothing, mask_source=args.mask_source, alpha=args.alpha)
    relight_video(model, args.video, args.masks, light, out, turntable_deg_per_s=args.turntable, lights=lights,
                  progress=not args.quiet, detail=not args.cnn_albedo, soft_edges=not args.hard_edges,
                  steady=not args.no_carry, hdr=args.hdr)
    return 0


_HARD_EDGES = ("paste the person with the mask as it is (default: a soft matte in the person's border band, "
               "the edge refined on the photo; a cut-out keeps its own alpha)")


def register(sub) -> None:
    p = add_command(sub, "relight-image", "Relight a photo of a person with any light (2D path: the CNN).",
                    "  relightnet relight-image person.jpg --light sunset --out relit.png    # mask: segmentation\n"
                    "  relightnet relight-image person.jpg --light sunset --out relit.jpg --quality 90\n"
                    "  relightnet relight-image person.png --mask mask.png --light sunset --out relit.png\n"
                    "  relightnet relight-image person.jpg --light light.npy --out relit.png --save-maps maps/\n"
                    "  relightnet relight-image person.png --mask m.png --light studio.exr --absolute --out r.png\n")
    p.add_argument("image", help="photo (PNG, JPEG, WebP, AVIF, TIFF, ...)")
    p.add_argument("--mask", help="person mask (white = person, or its alpha); default: the photo's alpha if it "
                   "has one, else the person segmentation (--mask-source)")
    add_mask_source_arg(p)
    p.add_argument("--light", required=True, help=LIGHT_HELP)
    p.add_argument("--out", required=True, help="relit image: .png (lossless), .jpg/.jpeg or .webp (--quality)")
    p.add_argument("--quality", type=quality, default=92, help="JPEG/WebP quality, 1 to 100 (default: %(default)s)")
    p.add_argument("--save-maps", metavar="DIR", help="also write albedo, shading, mask, transport, lights")
    p.add_argument("--absolute", action="store_true",
                   help="use the light at its own scale (default: keep the photo's exposure)")
    p.add_argument("--cnn-albedo", action="store_true",
                   help="relight the CNN's albedo (at its working size) instead of the photo divided by the "
                        "predicted shading (the default, which keeps the photo's detail)")
    p.add_argument("--hard-edges", action="store_true", help=_HARD_EDGES)
    add_model_args(p)
    p.set_defaults(func=run)

    p = add_command(sub, "relight-video", "Relight a video of a person frame by frame (2D path), streaming.",
                    "  relightnet relight-video clip.mp4 --light sunset --out relit.mp4      # masks: segmentation\n"
                    "  relightnet relight-video clip.mp4 --masks masks/ --light sunset --out relit.mp4\n"
                    "  relightnet relight-video clip.mp4 --masks masks.mp4 --light studio --turntable 30 --out t.mp4\n"
                    "  relightnet relight-video iphone_hlg.mov --light sunset --hdr --out relit_hdr.mp4  # HDR kept\n")
    p.add_argument("video", help="input video (mp4, mkv, ...)")
    p.add_argument("--masks", help="folder of per-frame mask images (sorted) or a mask video (default: the person "
                   "segmentation, tracked from frame to frame; --mask-source)")
    add_mask_source_arg(p)
    p.add_argument("--light", required=True, help=LIGHT_HELP)
    p.add_argument("--out", required=True, help="output video (.mp4 or .mkv)")
    p.add_argument("--turntable", type=float, default=0.0, help="turn the light about the up axis, degrees/second")
    p.add_argument("--smoothing", choices=STREAMING_SMOOTHING, default="auto",
                   help=smoothing_help(STREAMING_SMOOTHING, "auto") + "; of the source-light estimate")
    p.add_argument("--alpha", type=pos_float, default=0.3,
                   help="ema: weight of the newest frame (default: %(default)g)")
    p.add_argument("--cnn-albedo", action="store_true",
                   help="relight the CNN's albedo instead of each frame divided by the predicted shading")
    p.add_argument("--hard-edges", action="store_true", help=_HARD_EDGES)
    p.add_argument("--no-carry", action="store_true",
                   help="relight every frame from its own prediction alone (default: the CNN's maps are carried "
                        "from frame to frame along the optical flow, so the person does not flicker)")
    p.add_argument("--hdr", action="store_true",
                   help="keep an HDR video (HLG or PQ) HDR: 10-bit BT.2020 with its transfer, HEVC in .mp4, ffv1 in "
                        ".mkv (default: tone-mapped to SDR, as the frames are read)")
    add_model_args(p)
    p.set_defaults(func=run_video)
