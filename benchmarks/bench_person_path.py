"""How closely ``avatar --replace-person`` follows a walking person, on generated targets.

The target is :func:`relightnet.pipeline.walk_target.walking_target` (Anny walking across a known
background, x264), whose true path (the root translation per frame) is known. The avatar's path is
:func:`relightnet.pipeline.clean_plate.stand_in`'s (masks from the person segmentation, as the job
uses, and from the generator's true masks). Positions are compared relative to each camera (the
target's default camera, the avatar's placed one), which is what puts the avatar where the person is
in the image: across the frame (x), up (y) and in depth (z), in centimetres, over the frames that
show the whole person and over all frames (entering and leaving included), beside the error of a
fixed place (the median placement, what the job did before).

    python benchmarks/bench_person_path.py                          # 1280x720 and 192x144, 24 frames
    python benchmarks/bench_person_path.py --sizes 640x360 --frames 48
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import table  # noqa: E402


def _eye(cam) -> torch.Tensor:
    V = cam.view[0].double()
    return -(V[:3, :3].T @ V[:3, 3])


def measure(size, frames: int, body, tmp: Path) -> list[list]:
    """Rows of the table for one target size: per mask source, the mean and max error per axis."""
    from relightnet.io import read_video
    from relightnet.pipeline.clean_plate import person_box, stand_in
    from relightnet.pipeline.walk_target import walking_target
    from relightnet.raster import default_camera

    wt = walking_target(tmp, size=size, n_frames=frames, suffix=".mp4", body=body)
    truth = torch.as_tensor(wt.path, dtype=torch.float64)
    truth[:, 1] = 0.0
    rel = truth - _eye(default_camera(size))
    whole = np.array([b is not None and not np.isnan(b[0])
                      for b in (person_box(m[..., 0] > 127) for m in read_video(wt.masks))])
    rows = []
    for source, masks in (("segmentation", None), ("true masks", wt.masks)):
        _, cam, off = stand_in(wt.video, tmp / "o.mp4", frames, body, target_masks=masks)
        err = (off.double() - _eye(cam) - rel).abs().numpy() * 100
        fixed = (-_eye(cam) - rel).abs().numpy() * 100
        rows.append([f"{size[1]}x{size[0]}", source, f"{whole.sum()}/{frames}",
                     " / ".join(f"{v:.1f}" for v in err[whole].mean(0)),
                     " / ".join(f"{v:.1f}" for v in err[whole].max(0)),
                     " / ".join(f"{v:.1f}" for v in err.mean(0)),
                     " / ".join(f"{v:.1f}" for v in fixed[whole].mean(0))])
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", nargs="+", default=["1280x720", "192x144"], help="W x H")
    ap.add_argument("--frames", type=int, default=24)
    a = ap.parse_args()
    from relightnet.body import AnnyBody

    body = AnnyBody()
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_path_") as d:
        for k, s in enumerate(a.sizes):
            W, H = (int(x) for x in s.split("x"))
            rows += measure((H, W), a.frames, body, Path(d) / str(k))
    print(f"avatar path vs the walking person's true path, {a.frames} frames; errors in cm, x / y / z "
          "(across / up / depth)")
    print(table(["target", "masks", "whole person in view", "mean error (in view)", "max error (in view)",
                 "mean error (all frames)", "fixed place, mean (in view)"], rows))


if __name__ == "__main__":
    main()
