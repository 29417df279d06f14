"""How much a processed video flickers beyond its source: the added-flicker ratio and the warp error.

:class:`FlickerMeter` takes a video's frames one at a time, each as the source frame, the
processed (relit) frame and the person's mask, and measures over the pixels of the person in
two consecutive frames t − 1 and t:

- **added flicker**: ``mean |out_t − out_{t−1}| / mean |src_t − src_{t−1}|`` (1.0: the output
  changes exactly as much as the footage; above it, the processing added flicker);
- **warp error**: ``mean |out_t − warp(out_{t−1})|`` where ``warp`` follows the source's optical
  flow (:func:`relightnet.segment.flow.backward_flow`), over the pixels whose flow is reliable
  (reliability > 0.5) and that showed the person in both frames; the same of the source itself
  is reported beside it (what the flow leaves even for the footage).

Frames are (H, W, 3) uint8 (or float in [0, 1]); values are reported on the [0, 1] scale.
"""

from __future__ import annotations

import numpy as np

from ..checks import InputError
from ..segment.flow import backward_flow, warp_back

__all__ = ["FlickerMeter"]


def _float(x) -> np.ndarray:
    a = np.asarray(x)
    return a.astype(np.float32) / 255 if a.dtype == np.uint8 else a.astype(np.float32)


class FlickerMeter:
    """Streaming flicker measures of a processed video against its source (module docstring).

    ``update(source, output, mask)`` per frame ((H, W, 3) each, mask (H, W) bool); :meth:`result`
    gives ``{"added_flicker", "warp_error", "source_warp_error", "pairs"}``.
    """

    def __init__(self) -> None:
        self._prev = None
        self._sum = dict.fromkeys(("out", "src", "warp_out", "warp_src"), 0.0)
        self._n = dict.fromkeys(("both", "warp"), 0)
        self.pairs = 0

    def update(self, source, output, mask) -> None:
        src, out, m = _float(source), _float(output), np.asarray(mask, dtype=bool)
        if src.shape != out.shape or src.ndim != 3 or src.shape[:2] != m.shape:
            raise InputError(f"flicker: expected (H, W, 3) frames and an (H, W) mask, got {src.shape}, "
                             f"{out.shape}, {m.shape}")
        if self._prev is not None and self._prev[0].shape == src.shape:
            self._pair(*self._prev, src, out, m)
        self._prev = (src, out, m)

    def _pair(self, src0, out0, m0, src1, out1, m1) -> None:
        both = m0 & m1
        nb = int(both.sum())
        if nb == 0:
            return
        self.pairs += 1
        self._sum["out"] += float(np.abs(out1 - out0)[both].sum())
        self._sum["src"] += float(np.abs(src1 - src0)[both].sum())
        self._n["both"] += nb * 3
        flow = backward_flow(np.moveaxis(src0, -1, 0), np.moveaxis(src1, -1, 0))

        def warp(x):
            return warp_back(x, flow.flow)

        ok = m1 & (flow.reliability > 0.5) & (warp(m0.astype(np.float32)) > 0.5)
        nw = int(ok.sum())
        if nw:
            self._sum["warp_out"] += float(np.abs(out1 - warp(out0))[ok].sum())
            self._sum["warp_src"] += float(np.abs(src1 - warp(src0))[ok].sum())
            self._n["warp"] += nw * 3

    def result(self) -> dict:
        if self._n["both"] == 0 or self._sum["src"] == 0:
            raise InputError("flicker: no two consecutive frames show the person (or the source never changes)")
        nw = max(self._n["warp"], 1)
        return {"added_flicker": self._sum["out"] / self._sum["src"], "warp_error": self._sum["warp_out"] / nw,
                "source_warp_error": self._sum["warp_src"] / nw, "pairs": self.pairs}
