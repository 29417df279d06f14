"""Light curves over time as a PNG: luminance of the DC and l = 1 coefficients (raw, smoothed, truth)."""

from __future__ import annotations

import io

import torch

from ..color import luminance

__all__ = ["light_curves_png"]

_COEFFS = ((0, "DC (l=0)"), (1, "l=1, m=-1 (y)"), (2, "l=1, m=0 (z)"), (3, "l=1, m=1 (x)"))


def light_curves_png(raw: torch.Tensor | None, smoothed: torch.Tensor, truth: torch.Tensor | None = None,
                     outliers: torch.Tensor | None = None, switches: torch.Tensor | None = None,
                     title: str = "") -> bytes:
    """PNG bytes plotting light sequences over time.

    Args:
        raw: (T, K, 3) per-frame estimates (dots) or None.
        smoothed: (T, K, 3) smoothed sequence (line).
        truth: (T, K, 3) true lights (dashed) or None.
        outliers: (T,) bool frames flagged as outliers (red crosses) or None.
        switches: (T,) bool segment starts (dotted vertical lines) or None.
        title: figure title.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    smoothed = smoothed.detach().cpu().float()
    t = range(smoothed.shape[0])
    coeffs = [c for c in _COEFFS if c[0] < smoothed.shape[1]]
    fig = Figure(figsize=(10, 2.2 * len(coeffs)), dpi=80)
    axes = fig.subplots(len(coeffs), 1, sharex=True, squeeze=False)[:, 0]
    sm_l = luminance(smoothed).numpy()
    raw_l = luminance(raw.detach().cpu().float()).numpy() if raw is not None else None
    tr_l = luminance(truth.detach().cpu().float()).numpy() if truth is not None else None
    out_t = outliers.nonzero().flatten().tolist() if outliers is not None else []
    sw_t = switches.nonzero().flatten().tolist() if switches is not None else []
    for ax, (k, name) in zip(axes, coeffs, strict=True):
        if raw_l is not None:
            ax.plot(t, raw_l[:, k], ".", color="0.6", ms=3, label="raw")
        ax.plot(t, sm_l[:, k], "-", color="tab:blue", lw=1.5, label="smoothed")
        if tr_l is not None:
            ax.plot(t, tr_l[:, k], "--", color="tab:green", lw=1.2, label="truth")
        if out_t and raw_l is not None:
            ax.plot(out_t, raw_l[out_t, k], "x", color="tab:red", ms=5, label="outlier")
        for s in sw_t:
            ax.axvline(s - 0.5, color="tab:orange", ls=":", lw=1)
        ax.set_ylabel(name, fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0].legend(fontsize=7, ncol=4, loc="upper right")
    axes[0].set_title(title, fontsize=9)
    axes[-1].set_xlabel("frame")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()
