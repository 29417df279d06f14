"""Smoother matrices: SciPy agreement, exact reproduction of polynomials and splines, segments, errors."""

import numpy as np
import pytest
import scipy.signal
import torch

from relightnet.checks import InputError
from relightnet.temporal import smoothing_matrix
from relightnet.temporal.smoothers import hermite_basis, hermite_matrix, poly_matrix, savgol_matrix

EIN = "ts,skc->tkc"


def test_savgol_matches_scipy():
    x = np.random.default_rng(0).normal(size=(41, 2))
    for window, degree in [(9, 2), (7, 3), (5, 0)]:
        ref = scipy.signal.savgol_filter(x, window, degree, axis=0, mode="interp")
        np.testing.assert_allclose(savgol_matrix(41, window, degree).numpy() @ x, ref, atol=1e-12)


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_polynomial_data_is_reproduced_exactly(degree, poly_lights):
    x = poly_lights(50, degree)
    for S in [poly_matrix(50, degree), poly_matrix(50, degree, window=11), savgol_matrix(50, 11, degree)]:
        torch.testing.assert_close(torch.einsum(EIN, S, x), x, rtol=0, atol=1e-10)
    # One degree lower does not reproduce it.
    assert (torch.einsum(EIN, poly_matrix(50, degree - 1), x) - x).abs().max() > 1e-3


def test_hermite_exact_properties(poly_lights):
    n = 61
    for tangents in ("catmull-rom", "free"):
        S = hermite_matrix(n, 8, tangents)
        torch.testing.assert_close(S @ S, S, rtol=0, atol=1e-10)  # a projection
        torch.testing.assert_close(S.sum(1), torch.ones(n, dtype=torch.float64))  # constants pass
    # Catmull-Rom tangents (2nd-order at the ends) reproduce quadratics; fitted tangents reproduce cubics.
    quad, cub = poly_lights(n, 2), poly_lights(n, 3)
    torch.testing.assert_close(torch.einsum(EIN, hermite_matrix(n, 8), quad), quad, rtol=0, atol=1e-10)
    torch.testing.assert_close(torch.einsum(EIN, hermite_matrix(n, 8, "free"), cub), cub, rtol=0, atol=1e-10)
    assert (torch.einsum(EIN, hermite_matrix(n, 8), cub) - cub).abs().max() > 1e-4  # CR is not cubic-exact
    # A spline built on the same knots is reproduced exactly, and interpolates its knot values.
    H = hermite_basis(n, 8)
    assert H.shape == (n, 9)  # knots at frames 0, 7.5, ..., 60
    knots = torch.randn(9, 9, 3, dtype=torch.float64)
    spline = torch.einsum("tm,mkc->tkc", H, knots)
    torch.testing.assert_close(torch.einsum(EIN, hermite_matrix(n, 8), spline), spline, rtol=0, atol=1e-10)
    torch.testing.assert_close(spline[::15], knots[::2], rtol=0, atol=1e-12)
    assert hermite_basis(n, 8, "free").shape == (n, 18)


def test_smoothing_matrix_is_block_diagonal_over_segments():
    sw = torch.zeros(30, dtype=torch.bool)
    sw[12] = True
    S = smoothing_matrix(30, "savgol", sw, window=5, degree=1)
    assert S[:12, 12:].abs().max() == 0 and S[12:, :12].abs().max() == 0
    torch.testing.assert_close(S[12:, 12:], savgol_matrix(18, 5, 1))
    torch.testing.assert_close(smoothing_matrix(30, "hermite", knot_spacing=6), hermite_matrix(30, 6))


def test_short_sequences():
    # Fewer frames than parameters: every frame is kept (degree and window shrink to fit).
    for n in (1, 2, 3):
        for S in (poly_matrix(n, 3), poly_matrix(n, 2, window=9), savgol_matrix(n, 9, 2),
                  hermite_matrix(n, 8, "free")):
            assert S.shape == (n, n)
            torch.testing.assert_close(S, torch.eye(n, dtype=torch.float64), rtol=0, atol=1e-10)
    # 3 frames, knots every 8: two knots with Catmull-Rom tangents = the least-squares line.
    line = torch.full((3, 3), 1 / 3, dtype=torch.float64) + torch.tensor([-1.0, 0, 1])[:, None] * torch.tensor(
        [-1.0, 0, 1], dtype=torch.float64
    ) / 2
    torch.testing.assert_close(hermite_matrix(3, 8), line)


def test_bad_options():
    with pytest.raises(InputError, match="method"):
        smoothing_matrix(10, "spline")
    with pytest.raises(InputError, match="unknown option"):
        smoothing_matrix(10, "hermite", window=5)
    with pytest.raises(InputError, match="odd"):
        savgol_matrix(10, 6)
    with pytest.raises(InputError, match="degree"):
        savgol_matrix(10, 5, 5)
    with pytest.raises(InputError, match="knot_spacing"):
        hermite_basis(10, 0)
    with pytest.raises(InputError, match="tangents"):
        hermite_basis(10, 4, "natural")
    with pytest.raises(ValueError):
        poly_matrix(0)
