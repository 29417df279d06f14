"""The demo's motion-transfer pieces: the generated source clip and the side-by-side writer (the whole
step runs in tests/pipeline/test_demo.py)."""

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.io import VideoWriter, read_video, video_info
from relightnet.pipeline.demo import side_by_side
from relightnet.pipeline.motion_demo import walking_source


def test_walking_source_writes_the_clip_of_its_motion(anny_body, tmp_path):
    motion = walking_source(tmp_path / "s.mkv", 64, 3, anny_body)
    frames = list(read_video(tmp_path / "s.mkv"))
    assert len(frames) == 3 and video_info(tmp_path / "s.mkv").size == (64, 64)
    assert motion["trans"].shape == (3, 3) and all(v.shape == (3, 3) for v in motion["pose"].values())
    # the person moves: consecutive frames differ where the legs swing, the background does not change
    assert 0 < np.abs(frames[2].astype(int) - frames[0].astype(int)).mean() < 40
    with pytest.raises(InputError, match="walking source"):
        walking_source(tmp_path / "x.mkv", 64, 1, anny_body)
    assert not (tmp_path / "x.mkv").exists()


def test_side_by_side_scales_to_the_first_height(tmp_path):
    a = np.full((32, 32, 3), 200, np.uint8)
    b = np.zeros((16, 24, 3), np.uint8)
    b[:, 12:] = 100
    for name, img, n in (("a.mkv", a, 3), ("b.mkv", b, 2)):
        with VideoWriter(tmp_path / name, fps=10) as v:
            for _ in range(n):
                v.write(img)
    frames = list(read_video(side_by_side(tmp_path / "s.mkv", [tmp_path / "a.mkv", tmp_path / "b.mkv"], 10)))
    assert len(frames) == 2  # the shortest
    f = frames[0].astype(int)
    assert f.shape == (32, 80, 3)  # 32 + 24·2
    assert np.abs(f[:, :32] - 200).max() <= 2 and np.abs(f[:, 36:54]).max() <= 2
    assert np.abs(f[:, 60:] - 100).max() <= 2  # bilinear upscaling keeps the flat halves (lossless ffv1)
