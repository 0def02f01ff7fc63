"""The integration's shortcuts give the bits of the general paths they skip: the affine
recursion's single segment without the gains' scan, the sines and cosines of a unit vector
where every radius is finite and positive, and several Savitzky–Golay derivatives of one
series at once; the angle from its half-angle tangent is arctan2's to 2 ulp."""

from __future__ import annotations

import numpy as np

from pipeline.continuous.filters import savgol_filter, savgol_filters
from pipeline.continuous.integrate import _affine_recursion, _polar, _unit
from pipeline.earth.frames import tangent_sin_cos


def test_bounded_affine_recursion_is_the_scanned_one_and_the_recursion() -> None:
    rng = np.random.default_rng(3)
    gain = 1.0 + rng.uniform(-1e-6, 1e-6, 50_000)
    forcing = rng.normal(0.0, 1e-5, 50_000)
    scanned = _affine_recursion(gain, forcing)
    bounded = _affine_recursion(gain, forcing, bounded=True)
    np.testing.assert_array_equal(bounded, scanned)
    x, want = 0.0, np.empty_like(forcing)  # the recursion step by step
    for k in range(forcing.size):
        x = gain[k] * x + forcing[k]
        want[k] = x
    np.testing.assert_allclose(bounded, want, rtol=0, atol=1e-13)


def test_unit_vector_by_division_and_at_odd_radii() -> None:
    y = np.array([3.0, -1.0, 0.0, 2.0])
    x = np.array([4.0, 0.0, -2.0, -2.0])
    sin, cos, r = _unit(y, x)
    np.testing.assert_array_equal(r, [5.0, 1.0, 2.0, np.sqrt(8.0)])
    np.testing.assert_array_equal(sin, y / r)
    np.testing.assert_array_equal(cos, x / r)
    # r = 0, infinite or NaN: the trig functions of arctan2 (finite where it is)
    sin, cos, r = _unit(np.array([0.0, np.inf, np.nan, 1.0]), np.array([0.0, 1.0, 1.0, 0.0]))
    np.testing.assert_array_equal(sin[[0, 1, 3]], [0.0, 1.0, 1.0])
    np.testing.assert_allclose(cos[[0, 1, 3]], [1.0, 0.0, 0.0], atol=1e-16)
    assert np.isnan(sin[2]) and np.isnan(cos[2])


def test_angle_from_its_half_angle_tangent_is_arctan2s() -> None:
    """Within 2 ulp of arctan2 over the circle, and the tangent's sine and cosine within
    1e-15 (4.5 ulp of 1) of the trig functions' (NumPy's own sin and cos differ in the last
    bits between its AVX2 and AVX-512 paths: 5e-16 at one of 100,000 angles); at zero, infinite and NaN radii, at ±π (the tangent
    infinite) and past an overflowing square (y tiny, x < 0) arctan2's own, signed zeros kept."""
    rng = np.random.default_rng(11)
    y, x = rng.normal(size=(2, 100_000))
    want = np.arctan2(y, x)
    angle, half, _, _, _ = _polar(y, x, "half")
    assert np.max(np.abs(angle - want) / np.spacing(np.abs(want))) <= 2.0
    sin, cos = tangent_sin_cos(half)
    np.testing.assert_allclose(sin, np.sin(want), rtol=0, atol=1e-15)
    np.testing.assert_allclose(cos, np.cos(want), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(_polar(y, x, "angle")[0], want)
    y = np.array([0.0, -0.0, 0.0, -0.0, 1.0, 0.0, np.inf, np.nan, 1e-300, 2.0])
    x = np.array([1.0, 1.0, -1.0, -1.0, 0.0, 0.0, np.inf, 1.0, -1.0, -np.inf])
    want = np.arctan2(y, x)
    angle, half, _, _, _ = _polar(y, x, "half")
    np.testing.assert_array_equal(angle, want)
    assert np.array_equal(np.signbit(angle), np.signbit(want))
    sin, cos = tangent_sin_cos(half)
    finite = ~np.isnan(want)
    np.testing.assert_allclose(sin[finite], np.sin(want[finite]), rtol=0, atol=2e-16)
    np.testing.assert_allclose(cos[finite], np.cos(want[finite]), rtol=0, atol=2e-16)
    assert np.isnan(sin[7]) and np.isnan(cos[7])
    angle, half, _, _, _ = _polar(y, x, "")
    assert angle.size == half.size == 0


def test_savgol_filters_are_each_filter_alone() -> None:
    rng = np.random.default_rng(5)
    md = 1500.0 + np.cumsum(rng.uniform(0.009, 0.011, 20_000))  # long: by FFT blocks
    for values, points in ((md, 201), (md[:900], 201), (md, 101)):
        together = savgol_filters(values, points, 3, (0, 1, 2), 0.01)
        for deriv, got in enumerate(together):
            np.testing.assert_array_equal(got, savgol_filter(values, points, 3, deriv, 0.01))
