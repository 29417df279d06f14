"""What keeping a clip HDR costs and keeps: ``relight-video`` (or ``--job avatar``) on an HLG clip, SDR
out beside ``--hdr``.

The clip is made from a real video with hand-made masks (``--video``, ``--masks``): its frames as linear
light with their highlights lifted above reference white (``x (1 + 3 x^4)``), written as 10-bit HLG
(:class:`relightnet.io.hdr_video.HdrVideoWriter`). Both runs relight it with the same light, in one
process each (``relightnet`` as a user runs it), side by side. Printed per run: wall seconds, peak memory
(each run's own max RSS), and for ``--hdr`` the share of the background whose HDR codes come back within
2 steps of the source's (lossy HEVC) and the share of the frame above reference white, source and output.

    python benchmarks/bench_hdr.py --video ../shared/real-video/turning.mp4 \\
        --masks ../shared/real-video/turning_masks.mkv --frames 24
    python benchmarks/bench_hdr.py --video ../shared/real-video/turning.mp4 \\
        --masks ../shared/real-video/turning_masks.mkv --frames 2 --scale 4.29   # 3088 x 4032, 12.45 MP

``--scale S`` enlarges the frames S times each way (bilinear, even sides; masks nearest) to see the
memory at the pixel limit. ``--job avatar`` runs ``avatar --motion walk`` over the clip (its person's
masks for the light) instead: its "background" is every pixel the avatar does not draw (:func:`untouched`).

    python benchmarks/bench_hdr.py --video ../shared/real-video/turning.mp4 \\
        --masks ../shared/real-video/turning_masks.mkv --frames 2 --scale 4.29 --job avatar
"""

from __future__ import annotations

import argparse
import itertools
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
from common import cpu_name, table

from relightnet.io import video_info


def make_clip(video, masks, n: int, folder: Path, scale: float = 1.0) -> tuple[Path, Path]:
    """The HLG clip and its mask folder (the first ``n`` frames, ``scale`` times larger each way)."""
    from torch.nn.functional import interpolate

    from relightnet.color import srgb_to_linear
    from relightnet.io import read_video, write_image
    from relightnet.io.hdr_video import HdrFormat, HdrVideoWriter
    from relightnet.io.video_masks import read_masks

    clip, mask_dir = folder / "hlg.mp4", folder / "masks"
    mask_dir.mkdir()
    _, mask_iter = read_masks(masks)
    with HdrVideoWriter(clip, HdrFormat("hlg"), fps=24) as w:
        for t, (f, m) in enumerate(itertools.islice(zip(read_video(video), mask_iter, strict=False), n)):
            lin = srgb_to_linear(torch.from_numpy(f).permute(2, 0, 1).float() / 255)
            if scale != 1:
                size = [2 * round(d * scale / 2) for d in lin.shape[1:]]
                lin = interpolate(lin[None], size=size, mode="bilinear")[0].clamp_(0, 1)
                m = interpolate(m[None, None], size=size)[0, 0]
            w.write(lin * (1 + 3 * lin**4))
            write_image(mask_dir / f"{t:03d}.png", m[..., None].expand(-1, -1, 3), srgb=False)
    return clip, mask_dir


_CHILD = ("import resource, sys\nfrom relightnet.cli import main\nrc = main(sys.argv[1:])\n"
          "sys.stderr.write(f'MAXRSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}\\n')\nsys.exit(rc)\n")


def run(job: str, clip: Path, masks: Path, out: Path, hdr: bool) -> tuple[float, float]:
    """Wall seconds and peak RSS in MiB of one ``relight-video`` or ``avatar`` in its own process."""
    args = (["relight-video", str(clip), "--masks", str(masks), "--light", "sunset"] if job == "relight-video" else
            ["avatar", "--target", str(clip), "--target-masks", str(masks), "--motion", "walk"])
    cmd = [sys.executable, "-c", _CHILD, "-q", *args, "--out", str(out)] + (["--hdr"] if hdr else [])
    t0 = time.perf_counter()
    done = subprocess.run(cmd, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    rss = [int(line.split()[1]) for line in done.stderr.splitlines() if line.startswith("MAXRSS")]
    return wall, rss[-1] / 1024


def untouched(job: str, clip: Path, masks: Path, sdr_out: Path):
    """(H, W) bool per frame, the pixels the job leaves as they are: outside the person and its soft edge
    (``relight-video``), or 4 pixels away from where the SDR run's output is more than 6 levels off the
    clip's SDR reading (``avatar``: the avatar drawn; H.264's own error stays below that)."""
    from relightnet.io import read_video
    from relightnet.io.video_masks import read_masks
    from relightnet.raster import dilate

    if job == "avatar":
        return (~dilate(torch.from_numpy((np.abs(a.astype(np.int16) - b) > 6).any(-1))[None, None].float(), 4)[0, 0]
                .bool() for a, b in zip(read_video(clip), read_video(sdr_out), strict=False))
    return (~dilate(m[None, None], 4)[0, 0].bool() for m in read_masks(masks)[1])


def fidelity(clip: Path, out: Path, regions) -> tuple[float, float, float]:
    """(share of background codes within 2 steps, share of source pixels above reference white, of output)."""
    from relightnet.io.hdr_video import linear_to_signal, read_linear_video, ycbcr_codes

    near = total = bright_in = bright_out = pixels = 0
    for a, b, bg in zip(read_linear_video(clip), read_linear_video(out), regions, strict=False):
        diff = (ycbcr_codes(linear_to_signal(a, "hlg")) - ycbcr_codes(linear_to_signal(b, "hlg"))).abs().amax(0)
        near += int((diff[bg] <= 2).sum())
        total += int(bg.sum())
        bright_in += int((a.amax(0) > 1).sum())
        bright_out += int((b.amax(0) > 1).sum())
        pixels += a.shape[1] * a.shape[2]
    return near / max(total, 1), bright_in / pixels, bright_out / pixels


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--video", required=True)
    ap.add_argument("--masks", required=True)
    ap.add_argument("--frames", type=int, default=24)
    ap.add_argument("--scale", type=float, default=1.0, help="enlarge the frames this many times each way")
    ap.add_argument("--job", choices=("relight-video", "avatar"), default="relight-video")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        clip, masks = make_clip(args.video, args.masks, args.frames, folder, args.scale)
        size = video_info(clip).size
        sdr_wall, sdr_mem = run(args.job, clip, masks, folder / "sdr.mp4", hdr=False)
        hdr_wall, hdr_mem = run(args.job, clip, masks, folder / "hdr.mp4", hdr=True)
        near, bright_in, bright_out = fidelity(clip, folder / "hdr.mp4",
                                               untouched(args.job, clip, masks, folder / "sdr.mp4"))
    n = args.frames
    print(f"{args.job} on a {n}-frame {size[1]}x{size[0]} HLG clip ({cpu_name()}, {torch.get_num_threads()} threads)")
    print(table(["output", "wall s", "frames/s", "peak MiB", "ratio to SDR"],
                [["SDR (default)", sdr_wall, n / sdr_wall, sdr_mem, 1.0],
                 ["--hdr", hdr_wall, n / hdr_wall, hdr_mem, hdr_wall / sdr_wall]]))
    print(table(["background codes within 2 steps", "source above ref. white", "output above ref. white"],
                [[f"{near:.1%}", f"{bright_in:.1%}", f"{bright_out:.1%}"]]))


if __name__ == "__main__":
    main()
