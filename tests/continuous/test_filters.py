"""The NumPy Savitzky–Golay filters and convolutions against SciPy's (scipy.signal), which
a continuous run no longer imports."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from pipeline.continuous.filters import convolve_same, savgol_coeffs, savgol_filter


@pytest.mark.parametrize(("points", "order", "deriv"), [(7, 3, 0), (101, 2, 1), (201, 3, 2)])
def test_savgol_matches_scipy(points: int, order: int, deriv: int) -> None:
    rng = np.random.default_rng(points)
    values = np.cumsum(rng.normal(size=3 * points))
    dt = 0.01
    want = signal.savgol_coeffs(points, order, deriv=deriv, delta=dt)
    got = savgol_coeffs(points, order, deriv, dt)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12 * np.abs(want).max())
    want = signal.savgol_filter(values, points, order, deriv=deriv, delta=dt)
    got = savgol_filter(values, points, order, deriv, dt)
    np.testing.assert_allclose(got, want, rtol=1e-8, atol=1e-9 * np.abs(want).max())


def test_convolve_same_matches_scipy_rows_and_series() -> None:
    rng = np.random.default_rng(1)
    kernel = rng.normal(size=31)
    series = rng.normal(size=500)
    rows = rng.normal(size=(4, 61))
    want = signal.oaconvolve(series, kernel, mode="same")
    np.testing.assert_allclose(convolve_same(series, kernel), want, atol=1e-12)
    want = signal.oaconvolve(rows, kernel[None, :], mode="same", axes=1)
    np.testing.assert_allclose(convolve_same(rows, kernel), want, atol=1e-12)
