"""Video files through PyAV: streaming reader and an atomic streaming writer.

``.mp4`` is written with libx264 (CRF 18, yuv420p: every player decodes it; 4:2:0 chroma needs even
sides, so an odd-sized frame is padded by one pixel, its last row or column repeated, with a warning),
tagged SDR BT.709; ``.mkv`` with the lossless ffv1 codec (exact 8-bit RGB round trip, tagged sRGB).
Frames keep the source's presentation times when given (:func:`frame_times`, ``write(frame, time=...)``;
:mod:`relightnet.io.timestamps`): a variable frame rate stays so, a late video stream keeps its offset from
the sound. Above 1080p libx264 looks ahead 4 frames and makes no B-frames (:data:`X264_LARGE`): the frames
it holds bound its memory (at 12.5 MP, 0.5 GB instead of 1 GB), for a somewhat larger file at the same
quality. Frames are (H, W, 3) uint8 sRGB, or float linear RGB that the writer converts; an HDR clip (HLG,
PQ) is read tone-mapped to SDR (:mod:`relightnet.io.hdr`).
"""

from __future__ import annotations

import contextlib
import logging
import math
from array import array
from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, check_shape
from .atomic import atomic_write, remove_stale, temp_path
from .hdr import content_peak, frame_to_rgb24, note_hdr, sdr_frame, tag_sdr
from .image import limit_hint, open_limited, to_uint8, upright
from .limits import check_pixels, check_video_expansion
from .timestamps import MKV_CLOCK, MP4_CLOCK, PtsClock, timeline_origin

logger = logging.getLogger(__name__)

__all__ = ["VideoInfo", "video_info", "count_frames", "frame_times", "read_video", "VideoWriter"]

_CODECS = {".mp4": ("libx264", "yuv420p", {"crf": "18", "preset": "veryfast"}), ".mkv": ("ffv1", "bgr0", {})}
#: libx264's options for frames above 1080p (:data:`X264_LARGE_PIXELS`): the frames it holds (lookahead,
#: B-frames) are what its memory grows with (module docstring).
X264_LARGE = {"rc-lookahead": "2", "bf": "0"}
X264_LARGE_PIXELS = 1920 * 1080
#: Frames above this many pixels into a lossless ffv1 .mkv get a warning: FFmpeg's ffv1 encoder holds
#: about 60-75 bytes a pixel for one frame (0.7-0.9 GiB at 12.5 MP, SECURITY.md), past the memory budget
#: at the pixel limit with a job's own work.
FFV1_LARGE_PIXELS = 8_000_000


@dataclass(frozen=True)
class VideoInfo:
    """n_frames (what the container says, 0 when it does not; for progress bars only: use
    :func:`count_frames` to size anything), fps, size (H, W)."""

    n_frames: int
    fps: float
    size: tuple[int, int]


def _open(path):
    import av

    from .probe import header_size

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: video file not found")
    try:
        size = header_size(path)  # an image format played as a video (GIF, WebP, TIFF): its canvas
        if size is not None:
            check_pixels(*size, f"{path}")
        return open_limited(path, "a video")  # frame size checked before any frame is decoded
    except InputError:
        raise
    except (av.error.FFmpegError, OSError, ValueError) as e:
        raise InputError(f"{path}: unreadable video ({type(e).__name__}: {e})") from None


def video_info(path) -> VideoInfo:
    """Frame count, frame rate and size (H, W) of a video file, as displayed (rotation applied)."""
    import av

    with contextlib.closing(_open(path)) as c:
        s = c.streams.video[0]
        fps = float(s.average_rate or s.guessed_rate or 30)
        size = (s.codec_context.height, s.codec_context.width)
        try:  # a phone video stored sideways says so in its display matrix, seen on the frames
            first = next(iter(c.decode(video=0)), None)
        except (av.error.FFmpegError, ValueError) as e:
            raise InputError(f"{path}: corrupt video ({type(e).__name__}: {e}{limit_hint()})") from None
        if first is None:
            raise InputError(f"{path}: no frame could be decoded (empty or corrupt video)")
        size = (first.height, first.width)
        if round(float(first.rotation) / 90) % 2:
            size = size[::-1]
        if not (math.isfinite(fps) and 0 < fps <= 1000):
            raise InputError(f"{path}: frame rate {fps:g} is not a usable video frame rate")
        return VideoInfo(max(int(s.frames or 0), 0), fps, size)


def count_frames(path) -> int:
    """Frames of a video, counted from the packets really in the file (demuxed, not decoded).

    The count a container states (an mp4's ``stts``) is a claim of the file: a 2 KB mp4 can
    say 20 million frames, so it is never used to size anything. Demuxing reads each packet's
    header and data only (milliseconds per thousand frames) and stops where the file's data ends.
    """
    h, w = video_info(path).size  # the size, rate and first frame checked as every reader does
    return _count_checked(path, w, h)


def _count_checked(path, width: int, height: int) -> int:
    """The packets of the video stream, refused when they decode to far more than the file
    holds (:func:`~relightnet.io.limits.check_video_expansion`: a decompression bomb)."""
    import av

    with contextlib.closing(_open(path)) as c:
        try:
            n = sum(1 for p in c.demux(video=0) if p.size)
        except (av.error.FFmpegError, ValueError) as e:
            raise InputError(f"{path}: corrupt video ({type(e).__name__}: {e})") from None
    check_video_expansion(n, width, height, Path(path).stat().st_size, f"{path}")
    return n


def frame_times(path) -> np.ndarray | None:
    """Presentation times of a video's frames, in display order, on the timeline relightnet's
    writers keep (:mod:`relightnet.io.timestamps`): seconds from the file's
    :func:`~relightnet.io.timestamps.timeline_origin`, so a video stream that starts 0.5 s after its
    sound begins at 0.5 and a variable frame rate shows in the steps.

    Read from the packets (demuxed, not decoded, as :func:`count_frames` does; packets the demuxer
    marks as discarded, which decode to no frame, are left out) and refused as it does when they
    decode to far more than the file holds; memory grows by 8 bytes a packet.

    Returns:
        (T,) float64 seconds, increasing, one per frame :func:`read_video` yields; None when the
        file's packets carry no timestamps.
    """
    import av

    h, w = video_info(path).size  # the size, rate and first frame checked as every reader does
    file_bytes = Path(path).stat().st_size
    pts = array("q")
    with contextlib.closing(_open(path)) as c:
        s = c.streams.video[0]
        origin, tb = timeline_origin(c), s.time_base
        try:
            for p in c.demux(s):
                if not p.size or p.is_discard:
                    continue
                if p.pts is None:
                    return None
                pts.append(p.pts)
                if len(pts) % 4096 == 0:  # refused while reading: a bomb's packets are never all held
                    check_video_expansion(len(pts), w, h, file_bytes, f"{path}")
        except (av.error.FFmpegError, ValueError) as e:
            raise InputError(f"{path}: corrupt video ({type(e).__name__}: {e})") from None
    check_video_expansion(len(pts), w, h, file_bytes, f"{path}")
    ticks = np.sort(np.frombuffer(pts, np.int64)).astype(np.float64)
    return ticks * tb.numerator / tb.denominator - origin  # pts × time base: one rounding (exact products)


def read_video(path) -> Iterator[np.ndarray]:
    """Yield the frames of a video one at a time (memory does not grow with length), upright
    (a display rotation stored by the camera is applied).

    Before the first frame is yielded, the file's packets are counted: a video that decodes to
    far more pixels than its file holds is refused (:func:`count_frames`).

    Yields:
        (H, W, 3) uint8 RGB frames.
    """
    import av

    with contextlib.closing(_open(path)) as c:
        try:
            peak = None
            for i, frame in enumerate(c.decode(video=0)):
                if i == 0:
                    _count_checked(path, frame.width, frame.height)
                    note_hdr(frame, path)
                    peak = content_peak(frame)  # one tone mapping for the clip: its first frame's metadata
                yield upright(frame_to_rgb24(frame, peak), frame.rotation)
        except InputError:
            raise
        except (av.error.FFmpegError, ValueError) as e:
            raise InputError(f"{path}: corrupt video ({type(e).__name__}: {e}{limit_hint()})") from None


class VideoWriter:
    """Streaming, atomic video writer: the file appears only when ``close()`` succeeds.

    ``audio_from``: a media file whose audio track goes under the video (see
    :func:`relightnet.io.audio.add_audio`); ignored when it has none.

    Timestamps: ``write(frame, time=t)`` shows the frame at ``t`` seconds (the times of
    :func:`frame_times` of ``audio_from``: the sound is then put on the same timeline, shifted by that
    file's :func:`~relightnet.io.timestamps.timeline_origin`), on a 1/90000 s clock in mp4 (1 ms in
    mkv), one tick after the previous frame at least. Frames written without a time follow the
    previous one at ``fps`` (all of them: a constant-rate video from 0, its sound as it is).

    ``gray``: the frames are grey (masks, R = G = B): an .mkv stores their first channel as one 8-bit plane,
    exactly (ffv1 ``gray``: at 12.5 MP its encoder holds ~0.5 GB instead of ~1 GB for ``bgr0``); an .mp4
    is written as usual. Readers get (H, W, 3) frames back either way.

    Example:
        >>> with VideoWriter("out.mp4", fps=30) as w:  # doctest: +SKIP
        ...     for frame in frames:
        ...         w.write(frame)  # (H, W, 3) uint8, or float linear RGB
        >>> with VideoWriter("out.mp4", fps=30, audio_from="phone.mp4") as w:  # doctest: +SKIP
        ...     for frame, t in zip(frames, frame_times("phone.mp4")):
        ...         w.write(frame, time=t)  # the phone's timing kept
    """

    def __init__(self, path, fps: float = 30.0, srgb: bool = True, audio_from=None, gray: bool = False) -> None:
        from .audio import has_audio

        self.path = Path(path)
        if self.path.suffix.lower() not in _CODECS:
            raise InputError(f"{self.path}: expected a video suffix in {sorted(_CODECS)}")
        if not fps > 0:
            raise InputError(f"fps: expected a positive frame rate, got {fps}")
        self.fps, self.srgb = fps, srgb
        self._gray = bool(gray) and _CODECS[self.path.suffix.lower()][0] == "ffv1"
        # With a sound track to carry over, the video goes to a hidden file first and
        # close() muxes the two into ``path``.
        self._audio_from = audio_from if audio_from is not None and has_audio(audio_from) else None
        if self._audio_from is None:
            self._video_path = self.path
            self._ctx = atomic_write(self.path)
            self._file = self._ctx.__enter__()
        else:  # a private temporary file (its name records this process, see io.atomic)
            remove_stale(self.path)
            self._video_path, self._ctx = temp_path(self.path, "video"), None
            self._file = open(self._video_path, "xb")
        self._container = None
        self._stream = None
        self._clock: PtsClock | None = None
        self._size: tuple[int, int] | None = None  # (H, W) of the frames given (before any padding)
        self._timed = False
        self.n_frames = 0

    def write(self, frame, time: float | None = None) -> None:
        """Append one frame: (H, W, 3) uint8, or float linear RGB (converted to sRGB 8-bit), shown at
        ``time`` seconds (None: one frame at ``fps`` after the previous one; class docstring)."""
        if isinstance(frame, torch.Tensor):
            frame = frame.detach().cpu()
        frame = self._pixels(frame)
        check_shape(frame, ["H", "W", 3], name=f"{self.path}: frame")
        h, w = frame.shape[:2]
        codec, pix_fmt = self._codec()[:2]
        if self._stream is None:
            self._open_stream(h, w)
        elif (h, w) != self._size:
            raise InputError(f"{self.path}: frame {self.n_frames} is {h}x{w}, expected {self._size[0]}x{self._size[1]}")
        if pix_fmt.startswith("yuv420") and (h % 2 or w % 2):  # 4:2:0 chroma: even sides (the module docstring)
            frame = np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
        vf = self._frame(frame)
        vf.pts, vf.time_base = self._clock.pts(time), self._clock.tick
        self._timed = self._timed or time is not None
        for packet in self._stream.encode(vf):
            self._container.mux(packet)
        self.n_frames += 1

    def _pixels(self, frame) -> np.ndarray:
        """A frame given to :meth:`write` as the (H, W, 3) array :meth:`_frame` encodes: uint8 sRGB."""
        if isinstance(frame, np.ndarray) and frame.dtype == np.uint8:
            return frame
        frame = to_uint8(torch.as_tensor(frame), srgb=self.srgb)
        return frame.numpy() if isinstance(frame, torch.Tensor) else frame

    def _frame(self, frame: np.ndarray):
        """The PyAV frame of (H, W, 3) pixels from :meth:`_pixels` (even sides for 4:2:0)."""
        return sdr_frame(frame, gray=self._gray, yuv=self._codec()[0] == "libx264")

    def _codec(self) -> tuple[str, str, dict]:
        """(encoder, pixel format, options) for this file's suffix."""
        codec, pix_fmt, opts = _CODECS[self.path.suffix.lower()]
        return codec, "gray" if self._gray else pix_fmt, opts

    def _tag(self, codec_context) -> None:
        """The colour tags of the stream (:func:`~relightnet.io.hdr.tag_sdr`)."""
        tag_sdr(codec_context, yuv=self._codec()[0] == "libx264")

    def _open_stream(self, h: int, w: int) -> None:
        """The container and the video stream, for frames of (h, w), made at the first frame."""
        import av

        codec, pix_fmt, opts = self._codec()
        even = pix_fmt.startswith("yuv420")
        if even and (h % 2 or w % 2):
            logger.warning("%s: odd frame size %dx%d (width x height): padded to %dx%d (the last %s repeated) "
                           "for yuv420p", self.path, w, h, w + w % 2, h + h % 2,
                           " and ".join(n for n, odd in (("column", w % 2), ("row", h % 2)) if odd))
        if codec == "libx264" and h * w > X264_LARGE_PIXELS:
            opts = {**opts, **X264_LARGE}
        if codec == "ffv1" and h * w > FFV1_LARGE_PIXELS:
            logger.warning("%s: a lossless .mkv of %dx%d frames: FFmpeg's ffv1 encoder holds about %.1f GiB for one "
                           "frame (an .mp4 output stays within the memory budget)", self.path, w, h,
                           h * w * 70 / 2**30)
        fmt = "mp4" if self.path.suffix.lower() == ".mp4" else "matroska"
        rate = Fraction(self.fps).limit_denominator(1001)
        self._clock = PtsClock(MP4_CLOCK if fmt == "mp4" else MKV_CLOCK, rate, f"{self.path}")
        self._container = av.open(self._file, mode="w", format=fmt)
        self._stream = self._container.add_stream(codec, rate=rate)
        self._stream.codec_context.time_base = self._stream.time_base = self._clock.tick
        self._stream.width, self._stream.height = (w + w % 2, h + h % 2) if even else (w, h)
        self._stream.pix_fmt = pix_fmt
        self._stream.options = opts
        self._tag(self._stream.codec_context)
        self._size = (h, w)

    def close(self) -> Path:
        """Flush the encoder and move the file into place (with the sound of ``audio_from``)."""
        import av

        if self._stream is None:
            self.abort()
            raise InputError(f"{self.path}: no frames were written")
        for packet in self._stream.encode():
            self._container.mux(packet)
        self._container.close()
        if self._ctx is not None:
            self._ctx.__exit__(None, None, None)
        else:
            self._file.close()
        if self._audio_from is not None:
            from .audio import add_audio

            try:
                add_audio(self._video_path, self._audio_from, self.path, duration=self._clock.end(),
                          origin=timeline_origin(self._audio_from) if self._timed else 0.0)
            except (InputError, av.FFmpegError, ValueError) as e:
                logger.warning("%s: written without sound: the audio of %s could not be added (%s)",
                               self.path, self._audio_from, e)
                self._video_path.replace(self.path)
            finally:
                self._video_path.unlink(missing_ok=True)
        return self.path

    def abort(self) -> None:
        """Drop the partial file."""
        with contextlib.suppress(Exception):
            if self._container is not None:
                self._container.close()
        if self._ctx is None:
            self._file.close()
            self._video_path.unlink(missing_ok=True)
            return
        with contextlib.suppress(RuntimeError):
            self._ctx.__exit__(RuntimeError, RuntimeError("aborted"), None)

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()
