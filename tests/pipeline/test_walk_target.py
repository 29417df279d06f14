"""The generated walking target: a person crossing a known background."""

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.io import read_video
from relightnet.pipeline.walk_target import walking_target


def test_the_person_crosses_a_background_that_shows_as_it_is(anny_body, tmp_path):
    wt = walking_target(tmp_path, size=(48, 64), n_frames=4, body=anny_body)  # lossless ffv1
    frames, masks = list(read_video(wt.video)), [m[..., 0] > 127 for m in read_video(wt.masks)]
    assert len(frames) == len(masks) == 4 and frames[0].shape == (48, 64, 3)
    cols = [np.nonzero(m)[1].mean() for m in masks if m.any()]
    assert len(cols) >= 3 and all(b > a for a, b in zip(cols, cols[1:], strict=False))  # walks toward +x
    assert wt.ever.any() and not wt.always.any()
    free = ~wt.ever
    for f in frames:  # where the person never is, every frame shows the true background
        assert np.array_equal(f[free], wt.background[free])
    with pytest.raises(InputError, match="walking target"):
        walking_target(tmp_path, n_frames=1, body=anny_body)
