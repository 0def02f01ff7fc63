"""The frame positions' least squares fitted for many stations at once: each station's
numbers those of its own fit made alone (numpy on the one matrix; bit for bit on the
machines measured, asserted within :data:`ULP` units in the last place, as CPUs' kernels may
differ in the last bits), the model's parameters recovered, and every reject as a station
alone gets it."""

from __future__ import annotations

import re

import numpy as np
import pytest

from pipeline.earth.frames import FloatArray
from pipeline.gyrocompass.earth_rate import StationReject
from pipeline.gyrocompass.fit import Design, Fit, design, fit_all


def one_fit(d: Design) -> Fit | str:
    """The fit of one station alone, numpy's routines on its own 2-D matrices (how the fit
    was made station by station), or the reason it is not made."""
    normal = d.a.T @ (d.a * d.w[:, None])
    if np.linalg.cond(normal) > 1e10:
        return "the frame positions do not span the circle (ill-conditioned fit)"
    cov = np.asarray(np.linalg.inv(normal), dtype=np.float64)
    params = cov @ (d.a.T @ (d.w * d.y))
    res = d.y - d.a @ params
    rows, columns = d.a.shape
    return Fit(
        uv=params[:2],
        cov=cov,
        bias=float(params[2]) if d.terms else 0.0,
        trend=float(params[3]) if d.terms == 2 else 0.0,
        rms=float(np.sqrt((res**2).mean())),
        chi2=float((d.w * res**2).sum()),
        dof=rows - columns,
    )


def station(
    rng: np.random.Generator, n: int, axes: int, terms: int, spanning: bool = True
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, int]:
    """A station's readings at n frame positions (an axial gyro column when axes is 3)."""
    alpha = rng.uniform(0, 2 * np.pi) + (
        np.radians(np.arange(n) * 360.0 / max(n, 2)) if spanning else np.zeros(n)
    )
    t = np.sort(rng.uniform(0, 600, n)) + rng.uniform(0, 1e5)
    gyro = rng.normal(0, 15, (n, axes))
    sigma = 10 ** rng.uniform(-3, 0, (n, axes))
    return alpha, t, gyro, sigma, terms


ULP = 2
"""units in the last place a stacked fit's numbers may differ by from a station's alone"""


def assert_same(a: Fit, b: Fit) -> None:
    for name in ("uv", "cov", "bias", "trend", "rms", "chi2"):
        np.testing.assert_array_max_ulp(getattr(a, name), getattr(b, name), maxulp=ULP)
    assert a.dof == b.dof


def test_stacked_fits_are_each_stations_own() -> None:
    """Stations of many shapes mixed (1–12 positions, one to three axes, no bias, a bias, a
    bias and a trend; some not spanning the circle): grouped by shape and stacked, each
    station's fit is the one it has alone, and an ill-conditioned one is rejected (never
    inverted: its singular matrix would make the whole stack's inverse fail)."""
    rng = np.random.default_rng(5)
    designs = []
    for _ in range(300):
        n, axes, terms = int(rng.integers(1, 13)), int(rng.integers(1, 4)), int(rng.integers(3))
        try:
            designs.append(design(*station(rng, n, axes, terms, rng.uniform() > 0.2)))
        except StationReject:
            continue  # too few positions for the unknowns
    fits = fit_all(designs)
    assert len(fits) == len(designs) > 150
    rejected = 0
    for d, fit in zip(designs, fits, strict=True):
        alone = one_fit(d)
        if isinstance(alone, str):
            assert isinstance(fit, StationReject) and str(fit) == alone
            rejected += 1
        else:
            assert isinstance(fit, Fit)
            assert_same(fit, alone)
    assert 10 < rejected < len(designs) / 2
    assert fit_all([]) == []


def test_the_model_is_recovered_with_bias_and_trend() -> None:
    """Noise-free readings of two transverse gyros, (u, v), biases and trends known: the fit
    gives them back (exact model, zero residuals)."""
    rng = np.random.default_rng(2)
    designs, truths = [], []
    for _ in range(20):
        u, v, bx, dx, by, dy = rng.normal(0, 10, 6) * [1, 1, 1, 1e-3, 1, 1e-3]
        alpha = rng.uniform(0, 2 * np.pi) + np.radians([0, 90, 180, 270, 360, 45])
        t = np.asarray(1000.0 + 60.0 * np.arange(6), dtype=np.float64)
        tau = t - t.mean()
        x = u * np.cos(alpha) + v * np.sin(alpha) + bx + dx * tau
        y = -u * np.sin(alpha) + v * np.cos(alpha) + by + dy * tau
        designs.append(design(alpha, t, np.stack([x, y], -1), np.full((6, 2), 0.1), 2))
        truths.append((u, v, bx, dx))
    for fit, (u, v, bx, dx) in zip(fit_all(designs), truths, strict=True):
        assert isinstance(fit, Fit)
        np.testing.assert_allclose(fit.uv, [u, v], atol=1e-9)
        assert fit.bias == pytest.approx(bx, abs=1e-9)
        assert fit.trend == pytest.approx(dx, abs=1e-12)
        assert fit.rms < 1e-9 and fit.dof == 12 - 6


def test_a_station_that_cannot_be_fitted_is_rejected_before_the_stack() -> None:
    rng = np.random.default_rng(1)
    alpha, t, gyro, sigma, _ = station(rng, 3, 1, 2)
    with pytest.raises(StationReject, match=re.escape("3 position(s) cannot resolve 4 unknowns")):
        design(alpha, t, gyro, sigma, 2)
    sigma[1, 0] = 0.0
    with pytest.raises(StationReject, match="gyro σ is zero"):
        design(alpha, t, gyro, sigma, 1)
