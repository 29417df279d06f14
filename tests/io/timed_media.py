"""Clips with known timing for the timestamp tests: frames at given presentation times and a sound
whose clicks mark known moments, and the measures of an output's sync against its source."""

from __future__ import annotations

from fractions import Fraction

import av
import numpy as np

#: A variable-frame-rate clip as phones record it: 1 s at 30 fps, then 1 s at 15 fps.
VFR_TIMES = [i / 30 for i in range(30)] + [1 + i / 15 for i in range(15)]
#: A clip whose video stream starts 0.5 s after its sound (30 fps for 1 s).
LATE_TIMES = [0.5 + i / 30 for i in range(30)]
#: The same two, short (for whole jobs): 0.2 s at 30 fps then 0.27 s at 15 fps; 0.2 s at 30 fps from 0.5 s.
VFR_SHORT = [i / 30 for i in range(6)] + [0.2 + i / 15 for i in range(4)]
LATE_SHORT = [0.5 + i / 30 for i in range(6)]

RATE = 22050  # audio sample rate
CLICK = RATE // 50  # a click: 20 ms of a 1 kHz tone at half scale


def write_timed_clip(path, times, clicks, audio_start: float = 0.0, acodec: str = "aac", fmt: str = "mp4",
                     size=(64, 48)):
    """Write ``path``: (H, W) = ``size`` frames shown at ``times`` (seconds, on a 1/90000 clock:
    libx264, B-frames and all) and a mono sound from ``audio_start`` to 0.1 s after the last frame,
    silent but for a click at each time of ``clicks``. Frame i is a grey background with a bright
    block (a person to relight) whose brightness codes nothing: frames are matched by index."""
    h, w = size
    c = av.open(str(path), "w", format=fmt)
    v = c.add_stream("libx264", rate=30)
    v.width, v.height, v.pix_fmt = w, h, "yuv420p"
    v.codec_context.time_base = v.time_base = Fraction(1, 90000)
    a = c.add_stream(acodec, rate=RATE, layout="mono")
    g = np.random.default_rng(0)
    for t in times:
        img = g.integers(40, 90, (h, w, 3), dtype=np.uint8)
        img[8 : h - 8, 14:30] = 180
        frame = av.VideoFrame.from_ndarray(img, format="rgb24")
        frame.pts, frame.time_base = round(t * 90000), Fraction(1, 90000)
        for p in v.encode(frame):
            c.mux(p)
    sound = np.zeros(round((times[-1] + 0.1 - audio_start) * RATE), np.float32)
    for t in clicks:
        k = round((t - audio_start) * RATE)
        sound[k : k + CLICK] = 0.5 * np.sin(2 * np.pi * 1000 * np.arange(CLICK) / RATE)
    resampler = av.AudioResampler(format=a.codec_context.format.name, layout="mono", rate=RATE)
    k0 = round(audio_start * RATE)
    for k in range(0, len(sound), 1024):
        frame = av.AudioFrame.from_ndarray(sound[None, k : k + 1024], format="flt", layout="mono")
        frame.sample_rate, frame.pts, frame.time_base = RATE, k0 + k, Fraction(1, RATE)
        for f in resampler.resample(frame):
            for p in a.encode(f):
                c.mux(p)
    for p in [*a.encode(None), *v.encode(None)]:
        c.mux(p)
    c.close()
    return path


def write_masks(folder, n: int, size=(64, 48)):
    """``folder`` with ``n`` masks of the bright block of :func:`write_timed_clip`'s frames."""
    from relightnet.io import write_image

    h, w = size
    folder.mkdir()
    m = np.zeros((h, w, 3), np.uint8)
    m[8 : h - 8, 14:30] = 255
    for t in range(n):
        write_image(folder / f"{t:03d}.png", m)
    return folder


def decoded_frame_times(path) -> np.ndarray:
    """(T,) seconds: the presentation time of each decoded video frame, as a player shows it."""
    with av.open(str(path)) as c:
        return np.array([float(f.time) for f in c.decode(video=0)])


def click_times(path) -> np.ndarray:
    """Seconds: where each click starts in the decoded sound (first sample above a quarter of full
    scale after 0.1 s of quiet), on the file's clock."""
    with av.open(str(path)) as c:
        rate = c.streams.audio[0].codec_context.sample_rate
        frames = list(c.decode(audio=0))
    x = np.abs(np.concatenate([f.to_ndarray()[0] for f in frames]))
    loud = np.flatnonzero(x > 0.25)
    starts = loud[np.r_[True, np.diff(loud) > rate // 10]] if len(loud) else loud
    return float(frames[0].time) + starts / rate


def av_offsets(src, out) -> np.ndarray:
    """(T,) seconds, one per frame: how much later frame t is shown against the sound in ``out`` than
    in ``src`` (the time from the first click to frame t, out minus src; frames matched by index)."""
    ts, to = decoded_frame_times(src), decoded_frame_times(out)
    cs, co = click_times(src), click_times(out)
    if len(ts) != len(to) or len(cs) != len(co):
        raise AssertionError(f"{out}: {len(to)} frames and {len(co)} clicks, the source {len(ts)} and {len(cs)}")
    return (to - co[0]) - (ts - cs[0])
