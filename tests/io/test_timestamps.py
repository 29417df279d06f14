"""The timeline the writers keep: frame times read from a file, the origin, the pts clock."""

from fractions import Fraction

import av
import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.io.timestamps import MKV_CLOCK, MP4_CLOCK, PtsClock, timeline_origin
from relightnet.io.video import frame_times
from tests.io.timed_media import LATE_TIMES, VFR_TIMES, decoded_frame_times, write_timed_clip


def test_frame_times_of_a_vfr_clip_are_its_presentation_times(tmp_path):
    clip = write_timed_clip(tmp_path / "vfr.mp4", VFR_TIMES, clicks=[1.0])
    t = frame_times(clip)
    assert t.dtype == np.float64 and t.shape == (45,)
    # Written on the 90 kHz clock: each time within half a tick of the one asked for.
    np.testing.assert_allclose(t, VFR_TIMES, rtol=0, atol=0.5 / 90000)
    np.testing.assert_allclose(np.diff(t)[[0, 28, 29, 30, 43]], [1 / 30, 1 / 30, 1 / 30, 1 / 15, 1 / 15],
                               rtol=0, atol=1 / 90000)
    # The same times the decoder gives the frames (libx264's B-frames reordered: packets sorted).
    np.testing.assert_array_equal(t, decoded_frame_times(clip))


def test_a_late_video_stream_keeps_its_offset_from_the_sound(tmp_path):
    late = write_timed_clip(tmp_path / "late.mp4", LATE_TIMES, clicks=[1.0])  # video from 0.5 s, sound from 0
    with av.open(str(late)) as c:
        assert timeline_origin(c) == 0.0
    np.testing.assert_allclose(frame_times(late), LATE_TIMES, rtol=0, atol=0.5 / 90000)
    # Sound starting after the video (a PCM track: no encoder delay): the video's start is the origin.
    early = write_timed_clip(tmp_path / "early.mkv", [0.2 + i / 30 for i in range(10)], clicks=[0.5],
                             audio_start=0.4, acodec="pcm_s16le", fmt="matroska")
    assert timeline_origin(early) == pytest.approx(0.2, abs=1e-9)  # a path or an open container
    np.testing.assert_allclose(frame_times(early), np.arange(10) / 30, rtol=0, atol=0.5e-3)  # mkv: a 1 ms clock


def test_pts_clock_rounds_to_its_tick_and_never_repeats(caplog):
    clock = PtsClock(MP4_CLOCK, Fraction(30))
    assert [clock.pts(t) for t in (0.5, 0.5 + 1 / 30, 0.5 + 1 / 30, 0.5, 0.6)] == [45000, 48000, 48001, 48002, 54000]
    assert caplog.text.count("is not after the previous frame's") == 1  # warned once
    assert clock.pts(None) == 57000  # no time: one frame at the rate (1/30 s) after the last time asked for
    assert clock.end() == pytest.approx(0.6 + 2 / 30)  # the last frame lasts as long as the step before it
    with pytest.raises(InputError, match="frame time nan: expected a finite number of seconds"):
        clock.pts(float("nan"))


def test_pts_clock_without_times_is_the_constant_rate():
    ntsc = PtsClock(MP4_CLOCK, Fraction(30000, 1001))
    assert [ntsc.pts(None) for _ in range(4)] == [0, 3003, 6006, 9009]  # exact: no drift over a long video
    mkv = PtsClock(MKV_CLOCK, Fraction(12))
    assert [mkv.pts(None) for _ in range(4)] == [0, 83, 167, 250]
