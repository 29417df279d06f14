"""Image metrics for comparing relit frames with the ground truth, inside a mask.

Images are in the CNN layout (B, C, H, W) — or (T, C, H, W) for a sequence — with values
on a [0, ``data_range``] scale (``relightnet compare`` passes sRGB-encoded images in [0, 1]);
masks are (B, H, W) (or (B, 1, H, W)), and a pixel counts when its mask value is > 0.5.
Every average runs over the masked pixels *and* the C channels. All results are float64.

- :func:`masked_rmse`: ``sqrt(mean (x − y)²)``.
- :func:`psnr`: ``10 log10(data_range² / MSE)``; ``+inf`` for identical images.
- :func:`ssim_map` / :func:`ssim`: the SSIM of Wang, Bovik, Sheikh & Simoncelli (2004) with an
  11-tap Gaussian window (σ = 1.5), ``C1 = (0.01·R)²``, ``C2 = (0.03·R)²``, local statistics
  with population (biased) variances, computed per channel with reflect padding so the map
  has the image's size; :func:`ssim` is the masked mean of the map. Pixels outside the mask
  still enter the windows of masked pixels within 5 px of its edge, so give both images
  the same content there (e.g. zero) when only the masked region should matter.
- :func:`temporal_error`: ``mean |(x_t − x_{t−1}) − (y_t − y_{t−1})|`` over the pixels
  masked in both frames t and t−1 (zero for an output that differs from the truth by a
  static offset: it measures flicker and lag, not a constant bias).
"""

from __future__ import annotations

import math

import torch

from ..checks import InputError, ShapeError, check_shape

__all__ = ["gaussian_window", "masked_rmse", "psnr", "ssim_map", "ssim", "temporal_error"]

_F64 = torch.float64


def _images(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor, lead: str = "B"):
    """Validate (B, C, H, W) pair and mask; return float64 images and a (B, 1, H, W) bool mask."""
    for name, x in (("pred", pred), ("target", target), ("mask", mask)):
        if not isinstance(x, torch.Tensor):
            raise InputError(f"{name}: expected a torch.Tensor, got {type(x).__name__}")
    dims = check_shape(pred, [lead, "C", "H", "W"], name="pred")
    check_shape(target, [lead, "C", "H", "W"], name="target", dims=dims)
    if mask.dim() == 4:
        check_shape(mask, [lead, 1, "H", "W"], name="mask", dims=dims)
    else:
        check_shape(mask, [lead, "H", "W"], name="mask", dims=dims)
        mask = mask[:, None]
    m = mask > 0.5 if mask.dtype != torch.bool else mask
    return pred.to(_F64), target.to(_F64).to(pred.device), m.to(pred.device)


def _masked_mean(x: torch.Tensor, m: torch.Tensor, what: str) -> torch.Tensor:
    """Mean of (B, C, H, W) ``x`` over the channels and the pixels of (B, 1, H, W) bool ``m`` → (B,)."""
    n = m.sum((1, 2, 3)) * x.shape[1]
    if bool((n == 0).any()):
        raise InputError(f"mask: empty for image(s) {torch.nonzero(n == 0).flatten().tolist()}: "
                         f"{what} needs at least one masked pixel")
    return (x * m).sum((1, 2, 3)) / n


def masked_rmse(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Root-mean-square error inside the mask.

    Args:
        pred, target: (B, C, H, W).
        mask: (B, H, W) or (B, 1, H, W); pixels with mask > 0.5 count.

    Returns:
        (B,) float64 RMSE over the masked pixels and all channels.

    Raises:
        InputError: an image's mask is empty.
    """
    x, y, m = _images(pred, target, mask)
    return _masked_mean((x - y) ** 2, m, "RMSE").sqrt()


def psnr(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor, data_range: float = 1.0) -> torch.Tensor:
    """Peak signal-to-noise ratio inside the mask, in dB.

    Args:
        pred, target: (B, C, H, W) on a [0, ``data_range``] scale.
        mask: (B, H, W) or (B, 1, H, W).
        data_range: the peak value R.

    Returns:
        (B,) float64 ``10 log10(R² / MSE)``; ``+inf`` where the images agree exactly in the mask.
    """
    if not data_range > 0:
        raise InputError(f"data_range: expected a positive number, got {data_range}")
    x, y, m = _images(pred, target, mask)
    mse = _masked_mean((x - y) ** 2, m, "PSNR")
    return 10 * torch.log10(data_range**2 / mse)  # mse == 0 → +inf


def gaussian_window(size: int = 11, sigma: float = 1.5) -> torch.Tensor:
    """The normalised 1D Gaussian window (size,) float64 of SSIM (odd ``size``)."""
    if int(size) != size or size < 1 or size % 2 == 0:
        raise InputError(f"window size: expected an odd positive integer, got {size!r}")
    if not sigma > 0:
        raise InputError(f"sigma: expected a positive number, got {sigma}")
    x = torch.arange(size, dtype=_F64) - (size - 1) / 2
    g = torch.exp(-(x**2) / (2 * sigma**2))
    return g / g.sum()


def _blur_matrix(n: int, g: torch.Tensor) -> torch.Tensor:
    """(n, n) matrix B with ``B @ x`` = the 1D filter ``g`` along x's first axis, reflect padding."""
    r = g.numel() // 2
    if r >= n:
        raise ShapeError(f"images: SSIM needs H, W > {r} (window {g.numel()}), got a side of {n}")
    src = torch.arange(n)[:, None] + torch.arange(-r, r + 1)[None]  # (n, window) source rows
    src = torch.where(src < 0, -src, torch.where(src > n - 1, 2 * (n - 1) - src, src))
    B = torch.zeros(n, n, dtype=g.dtype, device=g.device)
    return B.index_put_((torch.arange(n)[:, None].expand_as(src).to(g.device), src.to(g.device)),
                        g.expand(n, -1).clone(), accumulate=True)


def _blur(x: torch.Tensor, g: torch.Tensor) -> torch.Tensor:
    """Separable Gaussian filter of (..., H, W) with reflect padding (same size), as two matmuls."""
    h, w = x.shape[-2:]
    return _blur_matrix(h, g) @ (x @ _blur_matrix(w, g).T)


def ssim_map(pred: torch.Tensor, target: torch.Tensor, data_range: float = 1.0, window: int = 11,
             sigma: float = 1.5, k1: float = 0.01, k2: float = 0.03) -> torch.Tensor:
    """The SSIM map (module docstring for the definition).

    Args:
        pred, target: (B, C, H, W) on a [0, ``data_range``] scale, H, W > ``window // 2``.
        data_range: the dynamic range R of the values.
        window, sigma: Gaussian window size (odd) and standard deviation.
        k1, k2: the stabilising constants (C1 = (k1 R)², C2 = (k2 R)²).

    Returns:
        (B, C, H, W) float64 SSIM per pixel and channel (1 where the images agree).
    """
    if not data_range > 0:
        raise InputError(f"data_range: expected a positive number, got {data_range}")
    dims = check_shape(pred, ["B", "C", "H", "W"], name="pred")
    check_shape(target, ["B", "C", "H", "W"], name="target", dims=dims)
    g = gaussian_window(window, sigma).to(pred.device)
    x, y = pred.to(_F64), target.to(_F64).to(pred.device)
    c1, c2 = (k1 * data_range) ** 2, (k2 * data_range) ** 2
    stats = _blur(torch.cat([x, y, x * x, y * y, x * y], 1), g)
    mx, my, xx, yy, xy = stats.chunk(5, dim=1)
    vx, vy, cxy = xx - mx * mx, yy - my * my, xy - mx * my
    return ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))


def ssim(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor, data_range: float = 1.0,
         **window) -> torch.Tensor:
    """Masked mean SSIM.

    Args:
        pred, target: (B, C, H, W) on a [0, ``data_range``] scale.
        mask: (B, H, W) or (B, 1, H, W).
        data_range: the dynamic range R.
        **window: ``window``, ``sigma``, ``k1``, ``k2`` of :func:`ssim_map`.

    Returns:
        (B,) float64 mean of the SSIM map over the masked pixels and the channels (1 for identical images).
    """
    x, y, m = _images(pred, target, mask)
    return _masked_mean(ssim_map(x, y, data_range, **window), m, "SSIM")


def temporal_error(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor,
                   reduction: str = "mean") -> torch.Tensor:
    """Temporal error: how much the frame-to-frame change of ``pred`` differs from the truth's.

    ``e = mean |(x_t − x_{t−1}) − (y_t − y_{t−1})|`` over the pixels masked in both frames
    t − 1 and t, and the channels.

    Args:
        pred, target: (T, C, H, W) sequences, T ≥ 2.
        mask: (T, H, W) or (T, 1, H, W).
        reduction: ``"mean"`` — one value pooled over all pairs (every counted pixel weighs
            the same) — or ``"none"`` — one value per pair (t − 1, t).

    Returns:
        () float64 for ``"mean"``; (T − 1,) float64 for ``"none"``, NaN for a pair whose masks
        do not overlap.

    Raises:
        InputError: T < 2, an unknown reduction, or no pixel masked in two consecutive frames.
    """
    if reduction not in ("mean", "none"):
        raise InputError(f"reduction: expected 'mean' or 'none', got {reduction!r}")
    x, y, m = _images(pred, target, mask, lead="T")
    if x.shape[0] < 2:
        raise InputError(f"pred: temporal error needs at least 2 frames, got {x.shape[0]}")
    both = m[1:] & m[:-1]
    d = ((x[1:] - x[:-1]) - (y[1:] - y[:-1])).abs() * both
    c = x.shape[1]
    n = both.sum((1, 2, 3)) * c
    if int(n.sum()) == 0:
        raise InputError("mask: no pixel is masked in two consecutive frames")
    s = d.sum((1, 2, 3))
    if reduction == "mean":
        return s.sum() / n.sum()
    return torch.where(n > 0, s / n.clamp_min(1), torch.full_like(s, math.nan))
