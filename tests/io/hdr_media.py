"""10-bit HDR test clips: HEVC 4:2:0 tagged BT.2020 with a given transfer (tests/io and tests/fuzz)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np


def write_hevc10(path, frames: Iterable[tuple[np.ndarray, np.ndarray, np.ndarray]], size: tuple[int, int], trc: int,
                 lossless: bool = False) -> None:
    """Write 10-bit 4:2:0 HEVC frames tagged BT.2020 (primaries and matrix), limited range and ``trc``.

    Args:
        path: the output file (.mp4 or .mkv).
        frames: per frame, the (Y (H, W), Cb (H/2, W/2), Cr (H/2, W/2)) uint16 code planes.
        size: (W, H), even.
        trc: the transfer's code (FFmpeg's AVColorTransferCharacteristic: 16 PQ, 18 HLG).
        lossless: x265's lossless mode (the codes decode exactly).
    """
    import av

    w, h = size
    with av.open(str(path), "w") as c:
        s = c.add_stream("libx265", rate=10)
        s.width, s.height, s.pix_fmt = w, h, "yuv420p10le"
        s.options = {"x265-params": ("lossless=1:" if lossless else "") + "bframes=0:log-level=error"}
        cc = s.codec_context
        cc.color_primaries, cc.color_trc, cc.colorspace, cc.color_range = 9, trc, 9, 1  # bt2020, bt2020nc, tv
        for i, planes in enumerate(frames):
            f = av.VideoFrame(w, h, "yuv420p10le")
            for plane, a in zip(f.planes, planes, strict=True):
                buf = np.zeros((a.shape[0], plane.line_size // 2), np.uint16)
                buf[:, :a.shape[1]] = a
                plane.update(buf.tobytes())
            f.pts = i
            for p in s.encode(f):
                c.mux(p)
        for p in s.encode():
            c.mux(p)


def write_hlg_copy(video, path, fps: float, gain: float):
    """An SDR clip's frames as a lossless HLG clip (ffv1): their linear light times ``gain`` (above 1.6 or so,
    their bright parts lie past the tone mapping's knee). Returns ``path``."""
    import torch

    from relightnet.color import srgb_to_linear
    from relightnet.io import read_video
    from relightnet.io.hdr_video import HdrFormat, HdrVideoWriter

    with HdrVideoWriter(path, HdrFormat("hlg"), fps=fps) as w:
        for f in read_video(video):
            w.write(srgb_to_linear(torch.from_numpy(f).permute(2, 0, 1).float() / 255) * gain)
    return path


def hlg_codes(light):
    """(3, H, W) linear light → its 10-bit HLG Y'CbCr codes, as the HDR writer stores them."""
    from relightnet.io.hdr_video import linear_to_signal, ycbcr_codes

    return ycbcr_codes(linear_to_signal(light, "hlg"))
