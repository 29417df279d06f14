"""HDR video kept HDR: a clip's frames read as linear light and written back as 10-bit HLG or PQ.

The reader (:mod:`relightnet.io.video`) tone-maps an HLG or PQ clip to SDR, which is what the
networks see and what a job writes by default. A job that keeps the clip HDR (``relight-video
--hdr``) reads the same frames a second time as linear light (:func:`read_linear_video`: BT.709
display light relative to the HDR reference white, :func:`~relightnet.io.hdr.frame_to_linear`), carries
its SDR edit over to them (:func:`hdr_from_sdr`) and writes them with :class:`HdrVideoWriter`:

1. linear BT.709 → BT.2020 primaries (the inverse of :data:`~relightnet.io.hdr.BT2020_TO_BT709`),
   negative components (outside BT.2020's gamut) set to 0;
2. the transfer (:func:`linear_to_signal`): PQ's inverse EOTF of the display light in cd/m², or for
   HLG the inverse of the reader's OOTF (nominal peak :data:`~relightnet.io.hdr.HLG_PEAK`) and the
   OETF;
3. R'G'B' → Y'CbCr with the BT.2020 non-constant-luminance matrix, limited range, 10 bits
   (:func:`ycbcr_codes`), chroma averaged over 2 x 2 pixels for 4:2:0;
4. ``.mp4``: HEVC (libx265, CRF 18, ``yuv420p10le``, tagged ``hvc1`` so that Apple players take it)
   with the PQ clip's MaxCLL / MaxFALL and mastering peak carried over when it had them; ``.mkv``:
   ffv1 ``yuv444p10le``. Both tagged BT.2020 primaries and matrix and the clip's transfer, so
   the package's own reader (and any HDR player) reads them as the source.

What the 10-bit round trip keeps is measured in tests/io/test_hdr_video.py.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import torch

from ..checks import InputError, check_shape
from ..color import srgb_to_linear
from .hdr import (
    _BT2020,
    _HLG,
    _LUMA_2020,
    _PQ,
    BT2020_TO_BT709,
    HLG_PEAK,
    REFERENCE_WHITE,
    _affine,
    frame_to_linear,
    hdr_metadata,
    hlg_oetf,
    pq_inverse_eotf,
    row_bands,
)
from .video import VideoWriter, _count_checked, _open

__all__ = ["HdrFormat", "hdr_format", "read_linear_video", "linear_to_signal", "ycbcr_codes", "hdr_from_sdr",
           "hdr_behind", "HdrVideoWriter", "HdrClip", "HDR_GAIN_MAX"]

_BT709_TO_BT2020 = np.linalg.inv(BT2020_TO_BT709)
_CODES = {".mp4": ("libx265", "yuv420p10le"), ".mkv": ("ffv1", "yuv444p10le")}
#: The largest factor by which :func:`hdr_from_sdr` scales the part of an HDR pixel above its SDR reading.
HDR_GAIN_MAX = 16.0
_EPS = 1e-3  # linear: the gain of a pixel black in SDR stays bounded


@dataclass(frozen=True)
class HdrFormat:
    """What an HDR clip's output keeps of it: ``transfer`` "hlg" or "pq"; a PQ clip's MaxCLL and
    MaxFALL and its mastering display's peak (cd/m², 0 when the clip states none; written into an
    HEVC output's SEI)."""

    transfer: str
    max_cll: int = 0
    max_fall: int = 0
    mastering_peak: float = 0.0

    def __post_init__(self) -> None:
        if self.transfer not in ("hlg", "pq"):
            raise ValueError(f"transfer: expected 'hlg' or 'pq', got {self.transfer!r}")


def hdr_format(path) -> HdrFormat | None:
    """The :class:`HdrFormat` of a video from its first frame, or None for an SDR video."""
    import av

    with contextlib.closing(_open(path)) as c:
        try:
            first = next(iter(c.decode(video=0)), None)
        except (av.error.FFmpegError, ValueError) as e:
            raise InputError(f"{path}: corrupt video ({type(e).__name__}: {e})") from None
        linear = None if first is None else frame_to_linear(first)
        if linear is None:
            return None
        cll, fall, master = hdr_metadata(first)
        return HdrFormat(linear[1], int(cll), int(fall), float(master))


def read_linear_video(path) -> Iterator[torch.Tensor]:
    """Yield the frames of an HLG or PQ video as linear light, upright, one at a time (as
    :func:`~relightnet.io.read_video` yields them tone-mapped, with its checks).

    Yields:
        (3, H, W) float32 linear BT.709 display light relative to
        :data:`~relightnet.io.hdr.REFERENCE_WHITE` (:func:`~relightnet.io.hdr.frame_to_linear`).

    Raises:
        InputError: the video is not HDR, or is corrupt.
    """
    import av

    with contextlib.closing(_open(path)) as c:
        try:
            for i, frame in enumerate(c.decode(video=0)):
                if i == 0:
                    _count_checked(path, frame.width, frame.height)
                linear = frame_to_linear(frame)
                if linear is None:
                    raise InputError(f"{path}: frame {i} is not HDR (HLG or PQ); expected an HDR video")
                k = round(float(frame.rotation) / 90) % 4
                yield torch.rot90(linear[0], k, dims=(1, 2)).contiguous() if k else linear[0]
        except InputError:
            raise
        except (av.error.FFmpegError, ValueError) as e:
            raise InputError(f"{path}: corrupt video ({type(e).__name__}: {e})") from None


def linear_to_signal(light: torch.Tensor, transfer: str) -> torch.Tensor:
    """Linear BT.709 light relative to reference white → BT.2020 R'G'B' signal (module docstring, steps
    1 and 2; the inverse of :func:`~relightnet.io.hdr.frame_to_linear`'s steps 2 and 3).

    Args:
        light: (3, ...) float linear light (1.0 = :data:`~relightnet.io.hdr.REFERENCE_WHITE`).
        transfer: "hlg" or "pq".

    Returns:
        (3, ...) float32 signal in [0, 1].
    """
    rgb = _affine(_BT709_TO_BT2020, light.float()).clamp_(min=0)
    if transfer == "pq":
        return pq_inverse_eotf(rgb * REFERENCE_WHITE).float()
    # the reader's OOTF: D = E Ys^0.2 P / W with Ys the luma of E, so luma(D) = Ys^1.2 P / W
    yd = rgb[0] * _LUMA_2020[0] + rgb[1] * _LUMA_2020[1] + rgb[2] * _LUMA_2020[2]
    ys = (yd * (REFERENCE_WHITE / HLG_PEAK)).clamp_min_(1e-12).pow_(1 / 1.2)
    scene = rgb / (ys.pow(0.2) * (HLG_PEAK / REFERENCE_WHITE))
    return hlg_oetf(scene).float()


def ycbcr_codes(signal: torch.Tensor, bits: int = 10) -> torch.Tensor:
    """BT.2020 R'G'B' → limited-range Y'CbCr codes (non-constant luminance; the inverse of
    :func:`~relightnet.io.hdr.ycbcr_to_rgb`).

    Args:
        signal: (3, ...) float R'G'B' in [0, 1].
        bits: bit depth of the codes.

    Returns:
        (3, ...) int32 Y', Cb, Cr codes, rounded and clipped to [0, 2^bits - 1].
    """
    kr, kb = _LUMA_2020[0], _LUMA_2020[2]
    y = signal[0] * kr + signal[1] * (1 - kr - kb) + signal[2] * kb
    cb, cr = (signal[2] - y) / (2 * (1 - kb)), (signal[0] - y) / (2 * (1 - kr))
    s = 2.0 ** (bits - 8)
    codes = torch.stack([y * (219 * s) + 16 * s, cb * (224 * s) + 128 * s, cr * (224 * s) + 128 * s])
    return codes.round_().clamp_(0, 2**bits - 1).to(torch.int32)


def hdr_from_sdr(edited: torch.Tensor, sdr: torch.Tensor, hdr: torch.Tensor) -> torch.Tensor:
    """Carry an edit of a frame's SDR reading over to its HDR original.

    ``edited`` is ``sdr`` changed by a job (the person relit, a soft composite): the HDR frame's own
    part above what its SDR reading shows (its highlights past the tone mapping's knee, its colours
    outside BT.709, 8-bit rounding) is kept, scaled by the edit's per-pixel gain:
    ``edited + (hdr - sdr) * gain`` with ``gain = (edited + eps) / (sdr + eps)`` clipped to
    [0, :data:`HDR_GAIN_MAX`]. A pixel the job left unchanged is the HDR original exactly; a relit
    pixel (a multiple of the photo) becomes that multiple of the HDR pixel.

    Args:
        edited: (3, H, W) the job's output, sRGB: float in [0, 1] or uint8.
        sdr: (3, H, W) the frame as the job read it (the reader's tone-mapped sRGB), float or uint8.
        hdr: (3, H, W) float32 the frame as linear light (:func:`read_linear_video`).

    Returns:
        (3, H, W) float32 linear light relative to reference white, for :class:`HdrVideoWriter`.
    """
    check_shape(hdr, [3, "H", "W"], name="hdr frame")
    check_shape(edited, list(hdr.shape), name="edited frame")
    check_shape(sdr, list(hdr.shape), name="sdr frame")
    out = torch.empty_like(hdr, dtype=torch.float32)
    for rows in row_bands(hdr.shape[1]):  # each pixel on its own: a band's temporaries, not a frame's
        e, s = (_linear(x[:, rows]) for x in (edited, sdr))
        gain = (e + _EPS).div_(s + _EPS).clamp_(0, HDR_GAIN_MAX)
        out[:, rows] = (hdr[:, rows] - s).mul_(gain).add_(e)
    return out


def _linear(srgb: torch.Tensor) -> torch.Tensor:
    """sRGB (uint8 codes or float in [0, 1]) → float32 linear light."""
    return srgb_to_linear(srgb.float() / 255 if srgb.dtype == torch.uint8 else srgb.float())


def hdr_behind(composite: torch.Tensor, sdr: torch.Tensor, hdr: torch.Tensor, drawn: torch.Tensor) -> torch.Tensor:
    """Carry a composite over a frame's SDR reading to its HDR original: the pixels the job drew
    (an avatar, its antialiased edge) are the composite's, every other pixel is the HDR frame's own:
    ``composite + (hdr - sdr) * (1 - drawn)``. Unlike :func:`hdr_from_sdr`, a drawn pixel takes
    nothing from the frame behind it (a gain between an avatar and the background it hides means
    nothing).

    Args:
        composite: (3, H, W) the job's output, sRGB: float in [0, 1] or uint8.
        sdr: (3, H, W) the frame as the job read it (the reader's tone-mapped sRGB), float or uint8.
        hdr: (3, H, W) float32 the frame as linear light (:func:`read_linear_video`).
        drawn: (H, W) bool or float in [0, 1], the share of each pixel the job drew.

    Returns:
        (3, H, W) float32 linear light relative to reference white, for :class:`HdrVideoWriter`.
    """
    check_shape(hdr, [3, "H", "W"], name="hdr frame")
    check_shape(composite, list(hdr.shape), name="composite frame")
    check_shape(sdr, list(hdr.shape), name="sdr frame")
    check_shape(drawn, list(hdr.shape[1:]), name="drawn")
    out = torch.empty_like(hdr, dtype=torch.float32)
    for rows in row_bands(hdr.shape[1]):
        e, s = (_linear(x[:, rows]) for x in (composite, sdr))
        out[:, rows] = (hdr[:, rows] - s).mul_(1 - drawn[rows].float()).add_(e)
    return out


class HdrVideoWriter(VideoWriter):
    """:class:`~relightnet.io.VideoWriter` for HDR frames: ``write`` takes (H, W, 3) or (3, H, W) float
    linear light relative to reference white (:func:`hdr_from_sdr`), written as ``fmt`` (module
    docstring; .mp4 HEVC 4:2:0, .mkv ffv1 4:4:4, 10 bits). Times, sound and atomicity as the SDR writer."""

    def __init__(self, path, fmt: HdrFormat, fps: float = 30.0, audio_from=None) -> None:
        super().__init__(path, fps=fps, srgb=False, audio_from=audio_from)
        if not isinstance(fmt, HdrFormat):
            raise InputError(f"{self.path}: expected an HdrFormat, got {type(fmt).__name__}")
        self.fmt = fmt

    def _pixels(self, frame) -> np.ndarray:
        x = torch.as_tensor(frame, dtype=torch.float32)
        if x.ndim == 3 and x.shape[0] == 3 and x.shape[-1] != 3:
            x = x.permute(1, 2, 0)
        if not all(bool(torch.isfinite(x[rows]).all()) for rows in row_bands(x.shape[0])):
            raise InputError(f"{self.path}: frame {self.n_frames} has non-finite values")
        return x.numpy()  # (H, W, 3), maybe a view of a (3, H, W) tensor: no copy of the frame

    def _codec(self) -> tuple[str, str, dict]:
        codec, pix_fmt = _CODES[self.path.suffix.lower()]
        if codec != "libx265":
            return codec, pix_fmt, {}
        params = ["log-level=error", "bframes=0"]  # with B-frames a clip of 1 or 2 frames cannot be muxed
        if self.fmt.transfer == "pq" and (self.fmt.max_cll or self.fmt.mastering_peak):
            params += ["hdr10=1", f"max-cll={self.fmt.max_cll},{self.fmt.max_fall}"]
            if self.fmt.mastering_peak:  # BT.2020 primaries, D65 white, in x265's units (0.00002, 0.0001 cd/m²)
                params.append(f"master-display=G(8500,39850)B(6550,2300)R(35400,14600)WP(15635,16450)"
                              f"L({round(self.fmt.mastering_peak * 10000)},1)")
        return codec, pix_fmt, {"crf": "18", "preset": "veryfast", "x265-params": ":".join(params)}

    def _tag(self, codec_context) -> None:
        cc = codec_context
        cc.color_primaries, cc.colorspace, cc.color_range = _BT2020, 9, 1  # BT.2020, BT.2020 ncl, limited
        cc.color_trc = _PQ if self.fmt.transfer == "pq" else _HLG
        if self._codec()[0] == "libx265":
            cc.codec_tag = "hvc1"

    def _frame(self, frame: np.ndarray):
        import av

        h, w = frame.shape[:2]
        light, codes = torch.from_numpy(frame).permute(2, 0, 1), torch.empty(3, h, w, dtype=torch.int32)
        for rows in row_bands(h):  # each pixel on its own: a band's temporaries, not a frame's
            codes[:, rows] = ycbcr_codes(linear_to_signal(light[:, rows], self.fmt.transfer))
        pix_fmt = self._codec()[1]
        vf = av.VideoFrame(w, h, pix_fmt)
        if pix_fmt.startswith("yuv420"):  # even sides (padded by write): chroma averaged over 2 x 2
            chroma = codes[1:].float().reshape(2, h // 2, 2, w // 2, 2).mean((2, 4)).round_().to(torch.int32)
            planes = [codes[0], chroma[0], chroma[1]]
        else:
            planes = list(codes)
        for plane, a in zip(vf.planes, planes, strict=True):
            buf = np.zeros((a.shape[0], plane.line_size // 2), np.uint16)
            buf[:, :a.shape[1]] = a.numpy()
            plane.update(buf.tobytes())
        vf.color_primaries, vf.color_trc, vf.colorspace, vf.color_range = (
            _BT2020, _PQ if self.fmt.transfer == "pq" else _HLG, 9, 1)
        return vf


class HdrClip:
    """An HDR clip's frames as linear light, handed out in step with a job's SDR frames of it, so that
    the job's edits are carried over (:func:`hdr_from_sdr`) to frames for :class:`HdrVideoWriter`.

    Args:
        path: the video (HLG or PQ).

    Raises:
        InputError: before any frame is read, when the video is SDR.
    """

    def __init__(self, path) -> None:
        fmt = hdr_format(path)
        if fmt is None:
            raise InputError(f"{path}: not an HDR video (its frames are not tagged HLG or PQ); --hdr expects one")
        self.path, self.fmt, self._frames, self._t = path, fmt, read_linear_video(path), 0

    def carry(self, edited: torch.Tensor, sdr: torch.Tensor, drawn: torch.Tensor | None = None) -> torch.Tensor:
        """The next frame's HDR output: ``edited`` ((H, W, 3) or (3, H, W), uint8 or float sRGB) the
        job's output for ``sdr`` ((3, H, W) or (H, W, 3) the frame as it read it) → (3, H, W) float32
        linear light: an edit of the frame carried over by :func:`hdr_from_sdr`, or with ``drawn`` ((H, W),
        what a composite drew over the frame) by :func:`hdr_behind`."""
        hdr = next(self._frames, None)
        if hdr is None:
            raise InputError(f"{self.path}: frame {self._t}: the HDR reading ended before the frames did")
        self._t += 1
        edited, sdr = (x.permute(2, 0, 1) if x.ndim == 3 and x.shape[-1] == 3 and x.shape[0] != 3 else x
                       for x in (edited, sdr))
        return hdr_from_sdr(edited, sdr, hdr) if drawn is None else hdr_behind(edited, sdr, hdr, drawn)
