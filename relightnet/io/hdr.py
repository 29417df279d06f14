"""HDR video frames (HLG or PQ, BT.2100) read as SDR sRGB: the colour maths the video reader uses.

A phone records HDR video as 10-bit Y'CbCr with BT.2020 primaries and the HLG (ARIB STD-B67) or PQ
(SMPTE ST 2084) transfer characteristic, tagged so in the stream. relightnet works in sRGB
(docs/design.md), so such a frame (:func:`hdr_transfer`) is converted on reading
(:func:`frame_to_rgb24`), in float32:

1. Y'CbCr → non-linear R'G'B' with the stream's matrix (BT.2020 non-constant luminance unless it
   says BT.709), its range (limited unless tagged full), at the stream's bit depth (chroma
   upsampled by swscale to 4:4:4, bilinear, and widened to 16 bits by a shift, then scaled back).
2. The transfer to display light in cd/m²: the PQ EOTF (:func:`pq_eotf`), or for HLG the inverse
   OETF (:func:`hlg_inverse_oetf`) and the OOTF of a display of nominal peak :data:`HLG_PEAK`
   (:func:`hlg_ootf`, system gamma 1.2, black 0).
3. BT.2020 → BT.709 primaries (:data:`BT2020_TO_BT709`, from the primaries' chromaticities, white
   D65); a colour outside BT.709's gamut is clipped to it (its negative components set to 0).
4. Tone mapping (:func:`tone_map`): display light divided by the HDR reference white
   :data:`REFERENCE_WHITE` (203 cd/m², ITU-R BT.2408), so reference white is SDR white 1.0 and all
   below the knee :data:`KNEE` is kept as it is; above it a shoulder (extended Reinhard on the
   excess, slope 1 at the knee) brings the content's peak (:func:`content_peak`: :data:`HLG_PEAK`, or
   for PQ the clip's MaxCLL, else its mastering display's peak, else :data:`PQ_PEAK`) to 1.0, the
   same for every frame of a clip (read from its first); it acts on max(R, G, B), so a
   colour keeps its hue and the ratios of its components. Reference white ends at 0.875 linear.
5. sRGB encoding, rounded to 8 bits.

The transfer curves of steps 2 and 5 are looked up in tables of 65537 steps (nearest; a 10-bit
signal's step is 75 of theirs), the 3 x 3 maps are matrix products: on one core a 720p frame takes
about 0.05 s, a 1080p one 0.15 to 0.2 s (FFmpeg's own conversion of an SDR frame: under 0.01 s).

Any other frame (SDR, tagged or not) decodes exactly as before: ``frame.to_ndarray(format="rgb24")``.
The transfer functions work on tensors of any shape (theirs is the input's); colours are channel
first, (3, ...).
"""

from __future__ import annotations

import logging
import math
import struct
from functools import lru_cache

import numpy as np
import torch

from ..color import linear_to_srgb

logger = logging.getLogger(__name__)

__all__ = ["HLG_PEAK", "PQ_PEAK", "REFERENCE_WHITE", "KNEE", "BT2020_TO_BT709", "hlg_oetf", "hlg_inverse_oetf",
           "hlg_ootf", "pq_eotf", "pq_inverse_eotf", "tone_map", "ycbcr_to_rgb", "hdr_transfer", "frame_to_linear",
           "frame_to_rgb24", "sdr_from_linear", "hdr_metadata", "content_peak", "note_hdr", "tag_sdr", "sdr_frame",
           "BAND_ROWS", "row_bands"]

HLG_PEAK = 1000.0  #: cd/m², the nominal peak of the HLG reference display (BT.2100)
PQ_PEAK = 1000.0  #: cd/m², the peak a PQ clip is taken to be mastered at (brighter content clips)
REFERENCE_WHITE = 203.0  #: cd/m², HDR reference (diffuse) white (BT.2408), SDR white 1.0
KNEE = 0.75  #: relative to reference white: below it the tone mapping is the identity

# HLG (BT.2100 table 5) and PQ (table 4) constants
_A, _B = 0.17883277, 1 - 4 * 0.17883277
_C = 0.5 - _A * math.log(4 * _A)
_M1, _M2 = 2610 / 16384, 2523 / 4096 * 128
_C1, _C2, _C3 = 3424 / 4096, 2413 / 4096 * 32, 2392 / 4096 * 32
_LUMA_2020 = (0.2627, 0.6780, 0.0593)
#: (Kr, Kb) of the Y'CbCr matrices by FFmpeg's colorspace code: BT.709 (1), BT.2020 ncl (9), cl (10, read as ncl)
_MATRIX = {1: (0.2126, 0.0722), 9: (0.2627, 0.0593), 10: (0.2627, 0.0593)}
_PQ, _HLG = 16, 18  # FFmpeg's color_trc codes: SMPTE ST 2084, ARIB STD-B67
_BT2020 = 9  # FFmpeg's color_primaries code
_STEPS = 65536  # of the curves' tables (_lookup)


def _rgb_to_xyz(xy) -> np.ndarray:
    """(3, 3) linear RGB → XYZ of primaries ``xy`` ((r, g, b) chromaticities), white D65."""
    p = np.array([[x / y, 1.0, (1 - x - y) / y] for x, y in xy]).T
    white = np.array([0.3127 / 0.3290, 1.0, (1 - 0.3127 - 0.3290) / 0.3290])
    return p * np.linalg.solve(p, white)


#: (3, 3) linear BT.2020 RGB → linear BT.709 RGB (``rgb709 = BT2020_TO_BT709 @ rgb2020``).
BT2020_TO_BT709 = np.linalg.solve(_rgb_to_xyz(((0.64, 0.33), (0.30, 0.60), (0.15, 0.06))),
                                  _rgb_to_xyz(((0.708, 0.292), (0.170, 0.797), (0.131, 0.046))))


def hlg_oetf(e: torch.Tensor) -> torch.Tensor:
    """HLG OETF: (...) scene linear light in [0, 1] → (...) signal in [0, 1]."""
    e = torch.as_tensor(e).clamp(0, 1)
    hi = _A * torch.log((12 * e - _B).clamp_min(1e-12)) + _C
    return torch.where(e <= 1 / 12, (3 * e).sqrt(), hi)


def hlg_inverse_oetf(v: torch.Tensor) -> torch.Tensor:
    """Inverse of :func:`hlg_oetf`: (...) signal in [0, 1] (clipped to it) → (...) scene linear light."""
    v = torch.as_tensor(v).clamp(0, 1)
    return torch.where(v <= 0.5, v * v / 3, (torch.exp((v - _C) / _A) + _B) / 12)


def hlg_ootf(rgb: torch.Tensor, peak: float = HLG_PEAK) -> torch.Tensor:
    """HLG OOTF: (3, ...) scene linear BT.2020 RGB in [0, 1] → (3, ...) display light in cd/m²
    on a display of nominal peak ``peak`` (system gamma ``1.2 + 0.42 log10(peak / 1000)``, black 0)."""
    gamma = 1.2 + 0.42 * math.log10(peak / 1000)
    ys = rgb[0] * _LUMA_2020[0] + rgb[1] * _LUMA_2020[1] + rgb[2] * _LUMA_2020[2]
    return rgb * (peak * ys.clamp_min(0) ** (gamma - 1))


def pq_eotf(v: torch.Tensor) -> torch.Tensor:
    """PQ EOTF: (...) signal in [0, 1] (clipped to it) → (...) display light in cd/m² (0 to 10000)."""
    p = torch.as_tensor(v).clamp(0, 1) ** (1 / _M2)
    return 10000 * ((p - _C1).clamp_min(0) / (_C2 - _C3 * p)) ** (1 / _M1)


def pq_inverse_eotf(nits: torch.Tensor) -> torch.Tensor:
    """Inverse of :func:`pq_eotf`: (...) cd/m² in [0, 10000] → (...) signal in [0, 1]."""
    y = (torch.as_tensor(nits) / 10000).clamp(0, 1) ** _M1
    return ((_C1 + _C2 * y) / (1 + _C3 * y)) ** _M2


def tone_map(rgb: torch.Tensor, peak: float) -> torch.Tensor:
    """HDR → SDR (module docstring, step 4), in place on ``rgb``.

    Args:
        rgb: (3, ...) linear BT.709 display light relative to reference white (1.0 = 203 cd/m²),
            non-negative.
        peak: the content's peak, relative to reference white (above :data:`KNEE`).

    Returns:
        (3, ...) linear SDR values in [0, 1]: identity below the knee, ``peak`` → 1.0.
    """
    m = rgb.amax(0)
    head, span = 1 - KNEE, peak - KNEE
    # the excess e over the knee, the shoulder KNEE + e (1 + e head / span²) / (1 + e / head)
    d = m.sub(KNEE).clamp_min_(0)
    shoulder = d.mul(head / span**2).add_(1).mul_(d).div_(d.div_(head).add_(1)).add_(KNEE)
    return rgb.mul_(shoulder.div_(m.clamp_min_(KNEE))).clamp_(0, 1)  # below the knee: KNEE / KNEE, 1 exactly


def ycbcr_to_rgb(yuv: torch.Tensor, bits: int, matrix: tuple[float, float], full_range: bool,
                 shift: int = 0) -> torch.Tensor:
    """Y'CbCr codes → non-linear R'G'B' (one affine map: a 3 x 3 matrix and an offset).

    Args:
        yuv: (3, ...) Y', Cb, Cr codes at ``bits`` bits (float32, or any dtype torch multiplies).
        bits: the bit depth of the codes.
        matrix: (Kr, Kb) of the Y'CbCr matrix (BT.2020: 0.2627, 0.0593).
        full_range: codes span [0, 2^bits - 1] instead of the limited 16..235 (240) scaled to ``bits``.
        shift: the codes are stored ``shift`` bits to the left (swscale widening them to 16 bits).

    Returns:
        (3, ...) float32 R'G'B', nominally in [0, 1] (not clipped).
    """
    kr, kb = matrix
    s = 2.0 ** (bits - 8)
    black, y_span, c_span = (0.0, 2**bits - 1, 2**bits - 1) if full_range else (16 * s, 219 * s, 224 * s)
    # R' = Y' + 2 (1 - Kr) Cr, B' = Y' + 2 (1 - Kb) Cb, G' = (Y' - Kr R' - Kb B') / Kg, on normalised Y', Cb, Cr
    kg = 1 - kr - kb
    m = np.array([[1, 0, 2 * (1 - kr)], [1, -2 * kb * (1 - kb) / kg, -2 * kr * (1 - kr) / kg], [1, 2 * (1 - kb), 0]])
    m = m / np.array([y_span, c_span, c_span]) / 2.0**shift
    offset = -m @ (np.array([black, 128 * s, 128 * s]) * 2.0**shift)
    return _affine(m, yuv.to(torch.float32), offset)


#: Rows of a frame its colour conversions take at a time (:func:`row_bands`): their temporaries (int64
#: lookup indices, float planes) are a band's, not a 12.5 MP frame's.
BAND_ROWS = 128


def row_bands(h: int, rows: int | None = None) -> list[slice]:
    """The slices of ``h`` rows, ``rows`` at a time (default :data:`BAND_ROWS`), that per-pixel
    conversions of a frame take."""
    rows = BAND_ROWS if rows is None else rows
    return [slice(r, min(r + rows, h)) for r in range(0, h, rows)]


def _affine(m: np.ndarray, x: torch.Tensor, offset: np.ndarray | None = None) -> torch.Tensor:
    """``m @ x + offset`` on (3, ...) float32 ``x``: m (3, 3), offset (3,) or None; one matrix product."""
    flat = x.reshape(3, -1)
    mt = torch.from_numpy(np.asarray(m, np.float32))
    if offset is None:
        return (mt @ flat).reshape(x.shape)
    return torch.addmm(torch.from_numpy(np.asarray(offset, np.float32))[:, None], mt, flat).reshape(x.shape)


@lru_cache(maxsize=4)
def _table(curve: str) -> torch.Tensor:
    """(65537,) a curve at the values 0, 1/65536, ..., 1 (:func:`_lookup`): "pq" display light relative
    to reference white, "hlg" scene light (:func:`hlg_inverse_oetf`; both float32), "srgb8" the sRGB
    encoding of linear light as rounded 8-bit codes (uint8)."""
    v = torch.linspace(0, 1, _STEPS + 1, dtype=torch.float64)
    if curve == "pq":
        return (pq_eotf(v) / REFERENCE_WHITE).float()
    if curve == "hlg":
        return hlg_inverse_oetf(v).float()
    return linear_to_srgb(v).mul_(255).round_().to(torch.uint8)


def _lookup(table: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """``table`` at the nearest of its steps to each value of ``v`` (...), clipped to [0, 1]; ``v`` is
    overwritten. At 1/65536 steps the rounding moves a 10-bit signal by 1/150 of its own step at most."""
    return torch.take(table, v.mul_(_STEPS).add_(0.5).clamp_(0, _STEPS).long())


def hdr_transfer(frame) -> str | None:
    """"hlg" or "pq" for a decoded PyAV Y'CbCr frame tagged with that transfer characteristic, else None
    (an RGB or gray frame, whatever its tag, is read as FFmpeg converts it)."""
    if frame.format.name.startswith(("rgb", "bgr", "gbr", "gray", "ya")):
        return None
    return {_HLG: "hlg", _PQ: "pq"}.get(int(frame.color_trc or 0))


def frame_to_linear(frame) -> tuple[torch.Tensor, str] | None:
    """A decoded HLG or PQ PyAV frame as linear light (module docstring, steps 1 to 3, without the
    clipping to BT.709's gamut), or None for any other frame (:func:`hdr_transfer`).

    Returns:
        ((3, H, W) float32 linear BT.709 display light relative to :data:`REFERENCE_WHITE` (1.0 =
        203 cd/m²; a colour outside BT.709's gamut keeps its negative components), "hlg" or "pq").
        The frame's display rotation is not applied.
    """
    transfer = hdr_transfer(frame)
    if transfer is None:
        return None
    bits, h, w = frame.format.components[0].bits, frame.height, frame.width
    yuv = frame.reformat(format="yuv444p16le")  # Y', Cb, Cr planes, chroma upsampled, codes << (16 - bits)
    planes = [np.frombuffer(p, np.uint16).reshape(h, p.line_size // 2)[:, :w] for p in yuv.planes]
    matrix, full = _MATRIX.get(int(frame.colorspace or 0), _MATRIX[9]), int(frame.color_range or 0) == 2
    bt2020, table = int(frame.color_primaries or 0) == _BT2020, _table(transfer)
    light = torch.empty(3, h, w)
    for rows in row_bands(h):  # each pixel on its own: a band's temporaries, not a frame's
        codes = torch.from_numpy(np.stack([p[rows] for p in planes]).astype(np.float32))
        band = _lookup(table, ycbcr_to_rgb(codes, bits, matrix, full_range=full, shift=16 - bits))
        if transfer == "hlg":  # the OOTF (hlg_ootf), in place: light * peak * Ys^(gamma - 1) / reference white
            ys = band[0] * _LUMA_2020[0] + band[1] * _LUMA_2020[1] + band[2] * _LUMA_2020[2]
            band.mul_(ys.clamp_min_(0).pow_(0.2).mul_(HLG_PEAK / REFERENCE_WHITE))
        light[:, rows] = _affine(BT2020_TO_BT709, band) if bt2020 else band
    del planes, yuv
    return light, transfer


def frame_to_rgb24(frame, peak: float | None = None) -> np.ndarray:
    """A decoded PyAV video frame as (H, W, 3) uint8 sRGB; an HLG or PQ frame tone-mapped to SDR
    (module docstring) with its content's ``peak`` in cd/m² (default: :func:`content_peak` of this
    frame; a clip passes its first frame's), any other one as FFmpeg converts it
    (``to_ndarray(format="rgb24")``)."""
    linear = frame_to_linear(frame)
    if linear is None:
        return frame.to_ndarray(format="rgb24")
    light = linear[0]
    return sdr_from_linear(light, content_peak(frame) if peak is None else peak).permute(1, 2, 0).contiguous().numpy()


def sdr_from_linear(light: torch.Tensor, peak: float) -> torch.Tensor:
    """HDR linear light (:func:`frame_to_linear`; (3, ...) float32, overwritten) → (3, ...) uint8 sRGB, as
    the reader shows it: clipped to BT.709's gamut, tone-mapped (:func:`tone_map`) to the content's
    ``peak`` in cd/m² (at least :data:`REFERENCE_WHITE`), sRGB-encoded and rounded."""
    flat, k, table = light.reshape(3, -1), max(peak, REFERENCE_WHITE) / REFERENCE_WHITE, _table("srgb8")
    out = torch.empty(flat.shape, dtype=torch.uint8)
    step = BAND_ROWS * 1024  # pixels at a time: each on its own, a band's temporaries
    for i in range(0, flat.shape[1], step):
        out[:, i:i + step] = _lookup(table, tone_map(flat[:, i:i + step].clamp_(min=0), k))
    return out.reshape(light.shape)


def hdr_metadata(frame) -> tuple[int, int, float]:
    """(MaxCLL, MaxFALL, mastering display peak) of a decoded PyAV frame's side data (an HEVC or AV1
    stream's SEI / metadata OBUs: FFmpeg's AVContentLightMetadata and AVMasteringDisplayMetadata),
    cd/m², 0 where the frame carries none."""
    cll = fall = 0
    master = 0.0
    for data in frame.side_data:
        kind, raw = str(data.type), bytes(data)
        if kind.endswith("CONTENT_LIGHT_LEVEL") and len(raw) >= 8:
            cll, fall = struct.unpack_from("<2I", raw)
        elif kind.endswith("MASTERING_DISPLAY_METADATA") and len(raw) >= 88:
            fields = struct.unpack_from("<22i", raw)  # 8 rationals of primaries and white, min, max, 2 flags
            if fields[21] and fields[19] > 0:  # has_luminance, max_luminance's denominator
                master = fields[18] / fields[19]
    return cll, fall, master


def content_peak(frame) -> float:
    """The peak in cd/m² a clip's tone mapping brings to SDR white, from its (first) decoded frame:
    :data:`HLG_PEAK` for HLG (scene-referred); for PQ its MaxCLL, else its mastering display's peak,
    else :data:`PQ_PEAK` (:func:`hdr_metadata`; values outside [:data:`REFERENCE_WHITE`, 10000] are
    not trusted)."""
    if hdr_transfer(frame) != "pq":
        return HLG_PEAK
    cll, _, master = hdr_metadata(frame)
    for nits in (cll, master):
        if REFERENCE_WHITE <= nits <= 10000:
            return float(nits)
    return PQ_PEAK


def note_hdr(frame, name) -> None:
    """Log, once for a clip (call it on its first frame), that its frames are HDR and read tone-mapped."""
    transfer = hdr_transfer(frame)
    if transfer is not None:
        logger.warning("%s: an HDR video (%s, %s primaries): its frames are tone-mapped to SDR sRGB "
                       "(reference white %g cd/m² as SDR white, peak %g cd/m²; relight-video and "
                       "avatar --hdr write it HDR)", name, transfer.upper(),
                       "BT.2020" if int(frame.color_primaries or 0) == _BT2020 else "BT.709",
                       REFERENCE_WHITE, content_peak(frame))


def tag_sdr(codec_context, yuv: bool) -> None:
    """Tag an encoder's output SDR: BT.709 primaries, transfer and matrix, limited range (``yuv``), or
    BT.709 primaries, the sRGB transfer and full range (RGB frames: ffv1 ``bgr0``, ``gray``)."""
    cc = codec_context
    cc.color_primaries, cc.color_trc = 1, (1 if yuv else 13)
    cc.colorspace, cc.color_range = (1, 1) if yuv else (0, 2)


def sdr_frame(rgb: np.ndarray, gray: bool, yuv: bool):
    """The PyAV frame given to an SDR encoder tagged by :func:`tag_sdr`.

    Args:
        rgb: (H, W, 3) uint8 sRGB (R = G = B when ``gray``).
        gray: make a one-plane ``gray`` frame of the first channel.
        yuv: make a ``yuv420p`` frame with the BT.709 matrix and limited range (swscale's default for
            an encoder's conversion is BT.601: a player reading the BT.709 tag would shift its colours).
    """
    import av

    plane = rgb[..., 0] if gray else rgb
    vf = av.VideoFrame.from_ndarray(np.ascontiguousarray(plane), format="gray" if gray else "rgb24")
    return vf.reformat(format="yuv420p", dst_colorspace="itu709", dst_color_range="MPEG") if yuv and not gray else vf
