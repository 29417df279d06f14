"""Sound for the videos relightnet writes: the source video's audio track carried over.

The relit or composited video is encoded first (video only); :func:`add_audio` then muxes
the source's audio under it, stream-copied where the container accepts the codec (AAC, MP3,
Opus, ... in ``.mp4``; anything in ``.mkv``) and re-encoded to AAC otherwise (e.g. PCM into
``.mp4``). Audio past the end of the video is dropped. With ``origin`` the sound is moved onto the
video's timeline (:mod:`relightnet.io.timestamps`): its timestamps lose the same seconds as the
source's frame times did, so it stays in sync with frames that keep their times.
"""

from __future__ import annotations

import contextlib
import heapq
import logging
from pathlib import Path

from ..checks import InputError
from .atomic import atomic_write

logger = logging.getLogger(__name__)

__all__ = ["has_audio", "add_audio"]

#: Audio codecs the mp4 muxer takes as they are.
_MP4_AUDIO = {"aac", "mp3", "alac", "opus", "ac3", "eac3", "flac"}


def has_audio(path) -> bool:
    """True when the media file has an audio stream (False for unreadable files)."""
    import av

    try:
        with av.open(str(path)) as c:
            return bool(c.streams.audio)
    except (av.FFmpegError, OSError):
        return False


def _packets(container, stream, end: float | None, origin: float = 0.0):
    """(time, n, packet) of one stream in decode order, up to ``end`` seconds, its timestamps
    ``origin`` seconds earlier."""
    shift = round(origin / stream.time_base) if origin else 0
    for n, p in enumerate(container.demux(stream)):
        if p.dts is None:  # the demuxer's flush packet
            continue
        if shift:
            p.dts -= shift
            p.pts = None if p.pts is None else p.pts - shift
        t = float(p.dts * p.time_base)
        if end is not None and t > end:
            break
        yield t, n, p


def _aac_packets(src, a_in, out_stream, end: float, origin: float = 0.0):
    """Decode the source audio and encode it to AAC for ``out_stream``, up to ``end`` seconds, its
    timestamps ``origin`` seconds earlier."""
    import av

    resampler = av.AudioResampler(format="fltp", layout=out_stream.layout, rate=out_stream.rate)

    def frames():  # resampled frames, then the resampler's and the encoder's flushes (None)
        for frame in src.decode(a_in):
            if frame.time is not None and frame.time - origin > end:
                break
            if origin and frame.pts is not None:
                frame.pts -= round(origin / frame.time_base)
            yield from resampler.resample(frame)
        yield from resampler.resample(None)
        yield None

    n = 0
    for f in frames():
        for p in out_stream.encode(f):
            n += 1
            yield (float(p.dts * p.time_base) if p.dts is not None else (0.0 if f is not None else end)), n, p


def add_audio(video, audio_from, out, duration: float | None = None, origin: float = 0.0) -> Path:
    """Write ``out``: the video stream of ``video`` (copied) with the audio of ``audio_from``.

    Args:
        video: a video file (its first video stream is copied bit for bit).
        audio_from: media file whose first audio stream is added (trimmed to the video's length).
        out: destination (``.mp4`` or ``.mkv``), written atomically.
        duration: where the video ends, in seconds (default: as its container says; audio is not
            trimmed when it says nothing).
        origin: seconds taken off the audio's timestamps: the
            :func:`~relightnet.io.timestamps.timeline_origin` of ``audio_from`` when the video's
            frames carry its frame times (:func:`relightnet.io.video.frame_times`); 0 leaves them as they are.

    Returns:
        The path written.

    Raises:
        InputError: ``audio_from`` has no audio stream or cannot be read.
    """
    import av

    out = Path(out)
    fmt = "mp4" if out.suffix.lower() == ".mp4" else "matroska"
    with contextlib.ExitStack() as stack:
        try:
            vin = stack.enter_context(av.open(str(video)))
            src = stack.enter_context(av.open(str(audio_from)))
        except (av.FFmpegError, OSError) as e:
            raise InputError(f"{audio_from}: cannot read its audio ({e})") from None
        if not src.streams.audio:
            raise InputError(f"{audio_from}: no audio stream")
        v_in, a_in = vin.streams.video[0], src.streams.audio[0]
        if a_in.codec_context is None:  # a damaged header can name a codec FFmpeg does not have
            raise InputError(f"{audio_from}: cannot read its audio (the codec is unknown or damaged)")
        end = duration if duration is not None else (
            float(v_in.duration * v_in.time_base) if v_in.duration else None)
        f = stack.enter_context(atomic_write(out))
        dst = stack.enter_context(av.open(f, mode="w", format=fmt))
        v_out = dst.add_stream_from_template(v_in)
        copy = fmt == "matroska" or a_in.codec_context.name in _MP4_AUDIO
        if copy:
            a_out = dst.add_stream_from_template(a_in)
            audio = _packets(src, a_in, end, origin)
        else:
            stereo = a_in.codec_context.layout.nb_channels != 1
            a_out = dst.add_stream("aac", rate=a_in.codec_context.sample_rate or 48000,
                                   layout="stereo" if stereo else "mono")
            audio = _aac_packets(src, a_in, a_out, end if end is not None else float("inf"), origin)
            logger.info("%s: audio %s re-encoded to AAC for %s", audio_from, a_in.codec_context.name, out.name)
        streams = {0: v_out, 1: a_out}
        video_packets = (((t, 0, n), p) for t, n, p in _packets(vin, v_in, None))
        audio_packets = (((t, 1, n), p) for t, n, p in audio)
        for (_, k, _), p in heapq.merge(video_packets, audio_packets, key=lambda kp: kp[0]):
            p.stream = streams[k]
            dst.mux(p)
    return out
