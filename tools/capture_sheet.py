"""The README's capture picture: a generated person, their captured avatar from four sides, and both relit.

Run: ``.venv/bin/python tools/capture_sheet.py --out docs/images/capture_sheet.jpg``

It runs the demo's capture step (:mod:`relightnet.pipeline.capture_demo`) at 384 px: a generated
person (bare Anny with a generated look) turns once under a warm light from the left (row 1: four
of the frames); ``relightnet capture`` makes it an avatar file; row 2 is the captured avatar from
the same four sides under a neutral light (the preview's views); row 3 is the captured person
walking in another video (the demo's target: a generated street-like clip under a turning night
light), lit by the light the CNN estimates there, beside the true person under the target's true
light, at three times. Not run by ``make``: it draws a picture.
"""

from __future__ import annotations

import argparse
import logging
import tempfile
from pathlib import Path

import torch
import torch.nn.functional as F

from relightnet.body import AnnyBody
from relightnet.capture import CapturedBody, load_avatar
from relightnet.color import linear_to_srgb
from relightnet.data import SynthConfig, generate_sequence
from relightnet.io import read_video
from relightnet.model import load_model
from relightnet.pipeline.backends import TorchPredictor
from relightnet.pipeline.capture_demo import capture_demo
from relightnet.pipeline.capture_preview import turntable_views
from relightnet.pipeline.demo import DEMO_CLIP, _write_target

logger = logging.getLogger("capture_sheet")

SIZE, FRAMES = 384, 48


def _row(images: list[torch.Tensor], crop: bool = True) -> torch.Tensor:
    """(H, W, 3) images → one row, each cropped to the person's columns ± a margin over black (``crop``)."""
    out = []
    for img in images:
        cols = torch.nonzero(img.amax((0, 2)) > 0.02).squeeze(1)
        a, b = (int(cols.min()), int(cols.max()) + 1) if cols.numel() and crop else (0, img.shape[1])
        m = SIZE // 12
        out.append(F.pad(img[:, max(a - m, 0):b + m].permute(2, 0, 1), (0, 6), value=1.0))
    return torch.cat(out, 2)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    torch.set_num_threads(2)
    body = AnnyBody()
    predictor = TorchPredictor(load_model())
    with tempfile.TemporaryDirectory() as d:
        sample = generate_sequence(SynthConfig(res=SIZE, n_dirs=64), "test", DEMO_CLIP, FRAMES, body=body)
        paths = _write_target(Path(d), sample)
        res = capture_demo(Path(d) / "capture", paths["target"], paths["masks"], paths["plate"],
                           torch.from_numpy(sample.arrays["light"]), SIZE, FRAMES, body, predictor, 64,
                           sample.meta["fps"], False)
        frames = [torch.from_numpy(f).float().div(255) for f in read_video(res["capture_source"])]
        moved = [torch.from_numpy(f).float().div(255) for f in read_video(res["capture_avatar"])]
        true = [torch.from_numpy(f).float().div(255) for f in read_video(res["capture_truth"])]
        avatar = load_avatar(res["capture_avatar_file"], body.num_verts)
    pick = [0, FRAMES // 4, FRAMES // 2, 3 * FRAMES // 4]
    views = [linear_to_srgb(v.clamp(0, 1)) for v in turntable_views(CapturedBody(body, avatar), SIZE)]
    times = [FRAMES // 6, FRAMES // 2, 5 * FRAMES // 6]
    pairs = [torch.cat([moved[t], true[t]], 1) for t in times]
    rows = [_row([frames[i] for i in pick], crop=False), _row(views), _row(pairs, crop=False)]
    width = max(r.shape[2] for r in rows)
    sheet = torch.cat([F.pad(r, (0, width - r.shape[2], 0, 8), value=1.0) for r in rows], 1)
    from PIL import Image

    pixels = (sheet.permute(1, 2, 0).clamp(0, 1) * 255).round().to(torch.uint8).numpy()
    Image.fromarray(pixels).save(args.out, quality=85)
    logger.info("seen %.1f%%, texture error %.3f, PSNR against the truth %.1f dB", 100 * res["capture_seen_share"],
                res["capture_albedo_error"], res["capture_psnr_db"])


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO)
    main()
