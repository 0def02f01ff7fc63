"""The NumPy Savitzky–Golay filters and convolutions against SciPy's (scipy.signal), which
a continuous run no longer imports; the shared-weight gradient and the azimuth in degrees
against NumPy's, to the bit."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from scipy import signal

from pipeline.continuous.filters import (
    TimeGradient,
    convolve_full,
    convolve_same,
    savgol_coeffs,
    savgol_filter,
)
from pipeline.continuous.series import azimuth_degrees


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
    want = signal.oaconvolve(rows, kernel[None, :], mode="full", axes=1)
    got = convolve_full(rows, kernel)
    assert got.shape == (4, 61 + 31 - 1)
    np.testing.assert_allclose(got, want, atol=1e-12)


def normal_solution(xs: list[Fraction], order: int, rhs: list[Fraction]) -> list[Fraction]:
    """The solution of the normal equations of a polynomial of degree ``order`` at the
    positions ``xs`` (Σ x^(i+j)) for the right-hand side ``rhs``, by Gauss–Jordan in exact
    rational arithmetic (the equations are positive definite)."""
    size = order + 1
    rows = [[sum(x ** (i + j) for x in xs) for j in range(size)] + [rhs[i]] for i in range(size)]
    for c in range(size):
        for r in range(size):
            if r != c:
                f = rows[r][c] / rows[c][c]
                rows[r] = [a - f * b for a, b in zip(rows[r], rows[c], strict=True)]
    return [rows[i][size] / rows[i][i] for i in range(size)]


def exact_savgol(points: int, order: int, deriv: int, delta: float) -> np.ndarray:
    """The Savitzky–Golay taps (reversed, as a convolution's) in exact rational arithmetic,
    then as long doubles."""
    half = points // 2
    xs = [Fraction(x) for x in range(half, half - points, -1)]
    size = order + 1
    rhs = [Fraction(math.factorial(deriv)) if i == deriv else Fraction(0) for i in range(size)]
    a = normal_solution(xs, order, rhs)
    taps = [sum(a[i] * x**i for i in range(size)) for x in xs]
    exact = [np.longdouble(t.numerator) / np.longdouble(t.denominator) for t in taps]
    return np.array(exact, dtype=np.longdouble) / np.longdouble(delta) ** deriv


@pytest.mark.parametrize(("points", "order", "deriv"), [(201, 3, 0), (201, 3, 1), (201, 3, 2)])
def test_savgol_of_a_km_odometer_is_the_exact_filter(points: int, order: int, deriv: int) -> None:
    """The odometer's fit (MD, speed, acceleration) of MD near 1,500 m against the exact
    Savitzky–Golay filter (rational taps, long-double sums) inside and the exact
    least-squares polynomials of the first and last windows at the ends: within 1e-14
    relative taps and 2e-12 of the fit (m, m/s, m/s²). SciPy's taps, and sums of products of
    the MD itself, were off by 9e-13 and 3e-9; its end fits by up to 1.5e-11."""
    rng = np.random.default_rng(deriv)
    dt, n = 0.01, 30_000
    speed = 1.0 + 0.5 * np.sin(np.arange(n) * dt / 30.0)
    md = 1500.0 + np.cumsum(speed) * dt + rng.normal(0.0, 1e-3, n)
    exact = exact_savgol(points, order, deriv, dt)
    taps = savgol_coeffs(points, order, deriv, dt)
    assert np.abs(taps - exact).max() <= 1e-14 * np.abs(exact).max()
    got = savgol_filter(md, points, order, deriv, dt)
    half = points // 2
    wide = md.astype(np.longdouble)
    at = np.arange(half, n - half, 89)
    want = np.array([np.dot(exact, wide[i - half : i + half + 1][::-1]) for i in at])
    assert np.abs(got[at] - want).max() <= 2e-12
    for window, where in ((slice(0, points), slice(0, half)), (slice(-points, None), None)):
        edge = exact_polyfit(md[window], order, deriv, dt)
        rows = np.arange(points)[where] if where else np.arange(points - half, points)
        fitted = got[window][rows]
        assert np.abs(fitted - edge[rows]).max() <= 2e-12  # SciPy's: off by up to 1.5e-11


def exact_polyfit(values: np.ndarray, order: int, deriv: int, delta: float) -> np.ndarray:
    """The ``deriv``-th derivative (sample interval ``delta``) of the least-squares
    polynomial of degree ``order`` through ``values`` at their positions 0, 1, …, solved in
    exact rational arithmetic, at each position (as floats)."""
    xs = [Fraction(x) for x in range(values.size)]
    ys = [Fraction(float(y)) for y in values]
    size = order + 1
    rhs = [sum(y * x**i for x, y in zip(xs, ys, strict=True)) for i in range(size)]
    coeffs = normal_solution(xs, order, rhs)
    scale = Fraction(delta) ** deriv
    out = [
        sum(coeffs[i] * math.perm(i, deriv) * x ** (i - deriv) for i in range(deriv, size)) / scale
        for x in xs
    ]
    return np.array([float(v) for v in out])


@pytest.mark.parametrize("taps", [101, 201])
def test_long_series_by_blocks_matches_scipy(taps: int) -> None:
    """A series of many FFT blocks (the last one partial) by overlap-add: SciPy's to the
    FFT's rounding (1e-16 of the values' magnitude, 1000 here)."""
    rng = np.random.default_rng(taps)
    kernel = rng.normal(size=taps)
    series = 1000.0 + np.cumsum(rng.normal(size=40_003))
    want = signal.oaconvolve(series, kernel, mode="same")
    got = convolve_same(series, kernel)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * np.abs(series).max())
    direct = np.convolve(series, kernel, mode="full")[taps // 2 : taps // 2 + series.size]
    assert not np.array_equal(got, direct)  # by FFT


@pytest.mark.parametrize("uniform", [True, False])
def test_time_gradient_is_numpys_gradient_to_the_bit(uniform: bool) -> None:
    rng = np.random.default_rng(7)
    t = np.full(400, 0.25) if uniform else 0.01 + rng.uniform(0.0, 0.002, size=400)
    t = np.concatenate([[12.0], 12.0 + np.cumsum(t)])
    gradient = TimeGradient(t)
    assert (np.diff(t) == np.diff(t)[0]).all() == uniform
    for series in (np.cumsum(rng.normal(size=t.size)), np.sin(t), np.zeros(t.size)):
        assert np.array_equal(gradient(series), np.gradient(series, t))
    two = t[:2]
    assert np.array_equal(TimeGradient(two)(np.array([1.0, 4.0])), np.gradient([1.0, 4.0], two))
    with pytest.raises(ValueError, match="two samples"):
        TimeGradient(t[:1])


@pytest.mark.filterwarnings("ignore:invalid value encountered in remainder")
def test_azimuth_degrees_is_numpys_modulo_to_the_bit() -> None:
    turns = np.linspace(-4 * np.pi, 4 * np.pi, 20_001)  # 0, ±360°, ±720° among them
    edges = [0.0, -0.0, -1e-300, -1e-17, 1e-17, 2 * np.pi, -2 * np.pi, np.nan, np.inf, -np.inf]
    azi = np.concatenate([turns, edges])
    degrees = np.degrees(azi) % 360.0
    want = np.where(degrees < 360.0, degrees, 0.0)  # −1e-17 rad: % 360 rounds to 360
    got = azimuth_degrees(azi)
    assert np.array_equal(got, want, equal_nan=True)
    assert np.array_equal(np.signbit(got), np.signbit(want))
    assert ((got >= 0.0) & (got < 360.0))[: turns.size].all()
