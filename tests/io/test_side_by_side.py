"""Videos side by side: scaled to the first one's height, as long as the shortest."""

import numpy as np

from relightnet.io import VideoWriter, read_video
from relightnet.io.side_by_side import write_side_by_side


def test_side_by_side_scales_to_the_first_height(tmp_path):
    a = np.full((32, 32, 3), 200, np.uint8)
    b = np.zeros((16, 24, 3), np.uint8)
    b[:, 12:] = 100
    for name, img, n in (("a.mkv", a, 3), ("b.mkv", b, 2)):
        with VideoWriter(tmp_path / name, fps=10) as v:
            for _ in range(n):
                v.write(img)
    frames = list(read_video(write_side_by_side(tmp_path / "s.mkv", [tmp_path / "a.mkv", tmp_path / "b.mkv"], 10)))
    assert len(frames) == 2  # the shortest
    f = frames[0].astype(int)
    assert f.shape == (32, 80, 3)  # 32 + 24·2
    assert np.abs(f[:, :32] - 200).max() <= 2 and np.abs(f[:, 36:54]).max() <= 2
    assert np.abs(f[:, 60:] - 100).max() <= 2  # bilinear upscaling keeps the flat halves (lossless ffv1)
