"""The demo's motion-transfer source clip (the whole step runs in tests/pipeline/test_demo.py)."""

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.io import read_video, video_info
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
