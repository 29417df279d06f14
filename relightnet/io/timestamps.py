"""The timeline of the videos relightnet writes: the source's presentation times, kept.

Phones record at a variable frame rate (VFR: 30 fps in daylight, 15 fps in the dark) and may
start the video stream after the sound. An output written at a constant average rate loses both:
its frames drift from the sound and its start offset is gone. So the writers keep the source's
times instead, on one timeline:

- **Origin.** Seconds on the output's timeline are the source's seconds minus its
  :func:`timeline_origin`, the earliest start among the streams an output keeps (the first video
  and the first audio stream): a video stream that starts 0.5 s after its sound has its first
  frame at 0.5 s, and the sound, shifted by the same origin, starts at 0.
- **Clock.** :class:`PtsClock` turns seconds into the output stream's ticks (1/90000 s in mp4,
  matroska's 1 ms in mkv) and never lets a frame's timestamp equal or precede the previous one's.

:func:`relightnet.io.video.frame_times` reads a video's frame times on this timeline;
:class:`relightnet.io.VideoWriter` writes them (``write(frame, time=...)``) and muxes the sound
against them (:func:`relightnet.io.audio.add_audio` with ``origin``).
"""

from __future__ import annotations

import logging
import math
from fractions import Fraction

from ..checks import InputError

logger = logging.getLogger(__name__)

__all__ = ["MP4_CLOCK", "MKV_CLOCK", "timeline_origin", "PtsClock"]

#: The tick of mp4 video written with times (the MPEG 90 kHz clock: every common frame rate lands on it).
MP4_CLOCK = Fraction(1, 90000)
#: Matroska stores timestamps in milliseconds, whatever the stream's time base.
MKV_CLOCK = Fraction(1, 1000)


def timeline_origin(container) -> float:
    """Seconds: the earliest start among the first video and the first audio stream of a media
    file (a path, or an open PyAV container): their ``start_time``; a stream that states none does
    not count; 0.0 when neither does."""
    if not hasattr(container, "streams"):
        import av

        with av.open(str(container)) as c:
            return timeline_origin(c)
    starts = []
    for streams in (container.streams.video, container.streams.audio):
        if streams and streams[0].start_time is not None and streams[0].time_base:
            starts.append(float(streams[0].start_time * streams[0].time_base))
    return min(starts, default=0.0)


class PtsClock:
    """Seconds → strictly increasing integer timestamps in ticks of ``tick`` seconds.

    ``pts(t)`` is ``round(t / tick)``, or one tick after the previous timestamp when that would not
    increase (a source with duplicate or decreasing times; warned once). ``pts(None)`` is one frame
    at ``rate`` (frames per second, a fraction) after the previous frame's time, 0 for the first:
    frames without times are written at that constant rate.
    """

    def __init__(self, tick: Fraction, rate: Fraction, what: str = "video") -> None:
        self.tick, self.frame, self.what = Fraction(tick), 1 / Fraction(rate), what
        self.time: Fraction | None = None  # the last frame's time as asked for (seconds)
        self.last: int | None = None  # the last frame's timestamp (ticks)
        self.step = max(round(self.frame / self.tick), 1)  # ticks between the last two frames
        self._warned = False

    def pts(self, time: float | None) -> int:
        """The timestamp (ticks) of the next frame, shown at ``time`` seconds (None: one frame later)."""
        if time is None:
            self.time = Fraction(0) if self.time is None else self.time + self.frame
        elif isinstance(time, bool) or not isinstance(time, (int, float)) or not math.isfinite(time):
            raise InputError(f"{self.what}: frame time {time!r}: expected a finite number of seconds")
        else:
            self.time = Fraction(time)
        ticks = round(self.time / self.tick)
        if self.last is not None and ticks <= self.last:
            if not self._warned:
                logger.warning("%s: frame time %.6f s is not after the previous frame's (%.6f s): written one "
                               "tick (%s s) after it", self.what, self.time, self.last * self.tick, self.tick)
                self._warned = True
            ticks = self.last + 1
        if self.last is not None:
            self.step = ticks - self.last
        self.last = ticks
        return ticks

    def end(self) -> float:
        """Seconds: where the video written so far ends (its last frame's time plus the last step)."""
        return float(((self.last or 0) + self.step) * self.tick)
