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
   excess, slope 1 at the knee) brings the content's peak (:data:`HLG_PEAK`, or :data:`PQ_PEAK`
   for PQ: the mastering display's metadata is not read) to 1.0; it acts on max(R, G, B), so a
   colour keeps its hue and the ratios of its components. Reference white ends at 0.875 linear.
5. sRGB encoding, rounded to 8 bits (:func:`~relightnet.io.image.to_uint8`).

Any other frame (SDR, tagged or not) decodes exactly as before: ``frame.to_ndarray(format="rgb24")``.
The transfer functions work on tensors; their shapes are the input's.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import torch

logger = logging.getLogger(__name__)

__all__ = ["HLG_PEAK", "PQ_PEAK", "REFERENCE_WHITE", "KNEE", "BT2020_TO_BT709", "hlg_oetf", "hlg_inverse_oetf",
           "hlg_ootf", "pq_eotf", "pq_inverse_eotf", "tone_map", "ycbcr_to_rgb", "hdr_transfer", "frame_to_rgb24",
           "note_hdr", "tag_sdr", "sdr_frame"]

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
    """HLG OOTF: (..., 3) scene linear BT.2020 RGB in [0, 1] → (..., 3) display light in cd/m²
    on a display of nominal peak ``peak`` (system gamma ``1.2 + 0.42 log10(peak / 1000)``, black 0)."""
    gamma = 1.2 + 0.42 * math.log10(peak / 1000)
    ys = rgb[..., 0] * _LUMA_2020[0] + rgb[..., 1] * _LUMA_2020[1] + rgb[..., 2] * _LUMA_2020[2]
    return rgb * (peak * ys.clamp_min(0) ** (gamma - 1)).unsqueeze(-1)


def pq_eotf(v: torch.Tensor) -> torch.Tensor:
    """PQ EOTF: (...) signal in [0, 1] (clipped to it) → (...) display light in cd/m² (0 to 10000)."""
    p = torch.as_tensor(v).clamp(0, 1) ** (1 / _M2)
    return 10000 * ((p - _C1).clamp_min(0) / (_C2 - _C3 * p)) ** (1 / _M1)


def pq_inverse_eotf(nits: torch.Tensor) -> torch.Tensor:
    """Inverse of :func:`pq_eotf`: (...) cd/m² in [0, 10000] → (...) signal in [0, 1]."""
    y = (torch.as_tensor(nits) / 10000).clamp(0, 1) ** _M1
    return ((_C1 + _C2 * y) / (1 + _C3 * y)) ** _M2


def tone_map(rgb: torch.Tensor, peak: float) -> torch.Tensor:
    """HDR → SDR (module docstring, step 4), in place on ``rgb`` when it is float32.

    Args:
        rgb: (..., 3) linear BT.709 display light relative to reference white (1.0 = 203 cd/m²),
            non-negative.
        peak: the content's peak, relative to reference white (above :data:`KNEE`).

    Returns:
        (..., 3) linear SDR values in [0, 1]: identity below the knee, ``peak`` → 1.0.
    """
    m = rgb.amax(-1, keepdim=True)
    head, span = 1 - KNEE, peak - KNEE
    d = (m - KNEE).clamp_min(0)
    shoulder = KNEE + d * (1 + d * head / span**2) / (1 + d / head)
    scale = torch.where(m > KNEE, shoulder / m.clamp_min(1e-12), torch.ones_like(m))
    return rgb.mul_(scale).clamp_(0, 1)


def ycbcr_to_rgb(yuv: torch.Tensor, bits: int, matrix: tuple[float, float], full_range: bool) -> torch.Tensor:
    """Y'CbCr codes → non-linear R'G'B'.

    Args:
        yuv: (..., 3) Y', Cb, Cr codes at ``bits`` bits (any float or integer dtype).
        bits: the bit depth of the codes.
        matrix: (Kr, Kb) of the Y'CbCr matrix (BT.2020: 0.2627, 0.0593).
        full_range: codes span [0, 2^bits - 1] instead of the limited 16..235 (240) scaled to ``bits``.

    Returns:
        (..., 3) float32 R'G'B', nominally in [0, 1] (not clipped).
    """
    kr, kb = matrix
    s = 2.0 ** (bits - 8)
    x = yuv.to(torch.float32)
    black, y_span, c_span = (0.0, 2**bits - 1, 2**bits - 1) if full_range else (16 * s, 219 * s, 224 * s)
    y, cb, cr = (x[..., 0] - black) / y_span, (x[..., 1] - 128 * s) / c_span, (x[..., 2] - 128 * s) / c_span
    r = y + 2 * (1 - kr) * cr
    b = y + 2 * (1 - kb) * cb
    g = (y - kr * r - kb * b) / (1 - kr - kb)
    return torch.stack((r, g, b), -1)


def hdr_transfer(frame) -> str | None:
    """"hlg" or "pq" for a decoded PyAV frame tagged with that transfer characteristic, else None."""
    return {_HLG: "hlg", _PQ: "pq"}.get(int(frame.color_trc or 0))


def frame_to_rgb24(frame) -> np.ndarray:
    """A decoded PyAV video frame as (H, W, 3) uint8 sRGB; an HLG or PQ frame tone-mapped to SDR
    (module docstring), any other one as FFmpeg converts it (``to_ndarray(format="rgb24")``)."""
    transfer = hdr_transfer(frame)
    if transfer is None or frame.format.name.startswith(("rgb", "bgr", "gbr", "gray")):
        return frame.to_ndarray(format="rgb24")
    from .image import to_uint8

    bits = frame.format.components[0].bits
    codes = torch.from_numpy(frame.reformat(format="yuv444p16le").to_ndarray().astype(np.float32))
    codes /= 2.0 ** (16 - bits)  # swscale widens the codes by a shift
    matrix = _MATRIX.get(int(frame.colorspace or 0), _MATRIX[9])
    rgb = ycbcr_to_rgb(codes, bits, matrix, full_range=int(frame.color_range or 0) == 2)
    if transfer == "pq":
        light, peak = pq_eotf(rgb), PQ_PEAK
    else:
        light, peak = hlg_ootf(hlg_inverse_oetf(rgb)), HLG_PEAK
    light /= REFERENCE_WHITE
    if int(frame.color_primaries or 0) == _BT2020:
        light = light @ torch.from_numpy(BT2020_TO_BT709.T.astype(np.float32))
    out = tone_map(light.clamp_(min=0), peak / REFERENCE_WHITE)
    return to_uint8(out).numpy()


def note_hdr(frame, name) -> None:
    """Log, once for a clip (call it on its first frame), that its frames are HDR and read tone-mapped."""
    transfer = hdr_transfer(frame)
    if transfer is not None:
        logger.warning("%s: an HDR video (%s, %s primaries): its frames are tone-mapped to SDR sRGB "
                       "(reference white %g cd/m² as SDR white)", name, transfer.upper(),
                       "BT.2020" if int(frame.color_primaries or 0) == _BT2020 else "BT.709",
                       REFERENCE_WHITE)


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
