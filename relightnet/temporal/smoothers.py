"""Linear smoother matrices for light sequences: polynomial, Savitzky–Golay, cubic Hermite spline.

Every offline method of :mod:`relightnet.temporal.offline` is a *linear smoother*:
the smoothed sequence is ``S @ x`` for a (T, T) matrix S that depends only on T,
the method's options and where the sequence is split — never on the data. These
functions build S (float64); :func:`smoothing_matrix` is the one entry point, so
a caller can build it once and reuse it for many sequences.

- ``"poly"``: polynomial regression of degree d — over the whole segment
  (``window=None``), or local (LOESS-style) with tricube weights over ``window``
  frames, the window shifted inward at the ends so it always holds ``window`` frames.
- ``"savgol"``: Savitzky–Golay: local polynomial with uniform weights over an odd
  ``window``; the ends use the first/last window's polynomial (scipy's ``mode="interp"``).
- ``"hermite"``: cubic Hermite spline with knots every ``knot_spacing`` frames
  (spread evenly so the first and last frames are knots). Tangents are
  Catmull–Rom central differences of the knot values (second-order one-sided at
  the ends), so the spline is linear in the knot values and the fit is one least
  squares problem, ``S = H H⁺``; ``tangents="free"`` fits the tangents too
  (the C¹ cubic spline space, which contains every cubic).
"""

from __future__ import annotations

import math

import torch

from ..checks import InputError
from ..names import OFFLINE_METHODS

__all__ = [
    "poly_matrix", "savgol_matrix", "hermite_basis", "hermite_matrix", "smoothing_matrix",
]

_F64 = torch.float64


def _check_n(n: int) -> int:
    if int(n) != n or n < 1:
        raise ValueError(f"n: expected a positive number of frames, got {n!r}")
    return int(n)


def _check_pos(value, name: str, minimum: int = 1) -> int:
    if isinstance(value, bool) or int(value) != value or value < minimum:
        raise InputError(f"{name}: expected an integer >= {minimum}, got {value!r}")
    return int(value)


def _local_poly(n: int, degree: int, window: int, tricube: bool) -> torch.Tensor:
    """(n, n) local polynomial smoother; window shifted inward at the ends."""
    w = min(window, n)
    if w % 2 == 0:
        w -= 1
    d = min(degree, w - 1)
    t = torch.arange(n)
    idx = (t - w // 2).clamp(0, n - w)[:, None] + torch.arange(w)  # (n, w)
    off = (idx - t[:, None]).to(_F64)
    u = off / (off.abs().amax(1, keepdim=True) + 1)  # |u| < 1 inside every window
    V = u[..., None] ** torch.arange(d + 1, dtype=_F64)  # (n, w, d+1)
    wts = (1 - u.abs() ** 3) ** 3 if tricube else torch.ones_like(u)
    VW = (V * wts[..., None]).transpose(1, 2)  # (n, d+1, w)
    rows = torch.linalg.solve(VW @ V, VW)[:, 0]  # value at u = 0 of the weighted LS polynomial
    return torch.zeros(n, n, dtype=_F64).scatter_(1, idx, rows)


def poly_matrix(n: int, degree: int = 2, window: int | None = None) -> torch.Tensor:
    """Polynomial regression smoother.

    Args:
        n: number of frames T.
        degree: polynomial degree d (lowered to fit short sequences).
        window: None for one polynomial over all frames; else an odd number of
            frames for local regression with tricube weights.

    Returns:
        (T, T) float64 matrix S; ``S @ x`` reproduces every polynomial of degree ≤ d.
    """
    n = _check_n(n)
    degree = _check_pos(degree, "degree", 0)
    if window is not None:
        return _local_poly(n, degree, _check_pos(window, "window"), tricube=True)
    d = min(degree, n - 1)
    u = torch.linspace(-1, 1, n, dtype=_F64) if n > 1 else torch.zeros(1, dtype=_F64)
    V = u[:, None] ** torch.arange(d + 1, dtype=_F64)
    return V @ torch.linalg.pinv(V)


def savgol_matrix(n: int, window: int = 9, degree: int = 2) -> torch.Tensor:
    """Savitzky–Golay smoother (uniform-weight local polynomial; end windows shifted inward).

    Args:
        n: number of frames T.
        window: odd window length (reduced for short sequences).
        degree: polynomial degree, < window.

    Returns:
        (T, T) float64 S, equal to ``scipy.signal.savgol_filter(..., mode="interp")``.
    """
    n = _check_n(n)
    window = _check_pos(window, "window")
    if window % 2 == 0:
        raise InputError(f"window: Savitzky-Golay needs an odd window, got {window}")
    degree = _check_pos(degree, "degree", 0)
    if degree >= window:
        raise InputError(f"degree: must be below the window ({window}), got {degree}")
    return _local_poly(n, degree, window, tricube=False)


def _tangent_matrix(m: int, h: float) -> torch.Tensor:
    """(M, M) D with tangents (d/dframe) = D @ knot values: Catmull–Rom, 2nd-order ends."""
    D = torch.zeros(m, m, dtype=_F64)
    if m == 2:
        D[:, 0], D[:, 1] = -1 / h, 1 / h
        return D
    i = torch.arange(1, m - 1)
    D[i, i - 1], D[i, i + 1] = -0.5 / h, 0.5 / h
    D[0, :3] = torch.tensor([-3.0, 4.0, -1.0], dtype=_F64) / (2 * h)
    D[-1, -3:] = torch.tensor([1.0, -4.0, 3.0], dtype=_F64) / (2 * h)
    return D


def hermite_basis(n: int, knot_spacing: float = 8, tangents: str = "catmull-rom") -> torch.Tensor:
    """Cubic Hermite spline basis evaluated at every frame.

    Knots: ``M = max(2, round((T−1)/knot_spacing) + 1)`` evenly spaced from frame 0
    to frame T−1.

    Args:
        n: number of frames T.
        knot_spacing: frames between knots (> 0).
        tangents: ``"catmull-rom"`` (tangents are finite differences of the knot
            values; parameters = M knot values) or ``"free"`` (parameters = M knot
            values then M tangents in units of value per knot interval).

    Returns:
        (T, P) float64 H with spline(frames) = H @ params, P = M or 2M.
    """
    n = _check_n(n)
    if not (isinstance(knot_spacing, (int, float)) and math.isfinite(knot_spacing) and knot_spacing > 0):
        raise InputError(f"knot_spacing: expected a positive number of frames, got {knot_spacing!r}")
    if tangents not in ("catmull-rom", "free"):
        raise InputError(f"tangents: expected 'catmull-rom' or 'free', got {tangents!r}")
    m = max(2, round((n - 1) / knot_spacing) + 1)
    h = (n - 1) / (m - 1) if n > 1 else 1.0
    t = torch.arange(n, dtype=_F64)
    seg = (t / h).floor().clamp(0, m - 2).long()
    s = t / h - seg
    s2, s3 = s * s, s * s * s
    h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2
    rows = torch.arange(n)
    P = torch.zeros(n, m, dtype=_F64)
    Q = torch.zeros(n, m, dtype=_F64)  # coefficients of the tangents times h
    P[rows, seg], P[rows, seg + 1] = h00, h01
    Q[rows, seg], Q[rows, seg + 1] = h10, h11
    if tangents == "free":
        return torch.cat([P, Q], 1)
    return P + Q @ (h * _tangent_matrix(m, h))


def hermite_matrix(n: int, knot_spacing: float = 8, tangents: str = "catmull-rom") -> torch.Tensor:
    """(T, T) float64 least-squares Hermite smoother ``H H⁺`` (see :func:`hermite_basis`)."""
    H = hermite_basis(n, knot_spacing, tangents)
    return H @ torch.linalg.pinv(H)


_BUILDERS = {
    "poly": (poly_matrix, ("degree", "window")),
    "savgol": (savgol_matrix, ("window", "degree")),
    "hermite": (hermite_matrix, ("knot_spacing", "tangents")),
}


def _check_method(method: str) -> None:
    if method not in _BUILDERS:
        raise InputError(f"method: expected one of {', '.join(OFFLINE_METHODS)}, got {method!r}")


def smoothing_matrix(n: int, method: str = "hermite", switches=None, **opts) -> torch.Tensor:
    """The (T, T) float64 smoother of ``method``, block-diagonal over segments.

    Args:
        n: number of frames T.
        method: one of :data:`relightnet.names.OFFLINE_METHODS`.
        switches: None, or (T,) bool marking the first frame of each new segment.
        **opts: the method's options (``degree``/``window`` for poly and savgol,
            ``knot_spacing``/``tangents`` for hermite).

    Returns:
        (T, T) S: ``smoothed = S @ x``.
    """
    _check_method(method)
    fn, names = _BUILDERS[method]
    bad = sorted(set(opts) - set(names))
    if bad:
        raise InputError(f"{method}: unknown option(s) {', '.join(bad)}; expected {', '.join(names)}")
    n = _check_n(n)
    starts = [0] if switches is None else [0] + [int(i) for i in torch.nonzero(torch.as_tensor(switches)).flatten()
                                                  if 0 < int(i) < n]
    bounds = sorted(set(starts)) + [n]
    if len(bounds) == 2:
        return fn(n, **opts)
    S = torch.zeros(n, n, dtype=_F64)
    for a, b in zip(bounds[:-1], bounds[1:], strict=False):
        S[a:b, a:b] = fn(b - a, **opts)
    return S
