"""Canonical-frame helpers: the half-angle sine and cosine, and their turned values."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.earth.frames import TURN_REACH, sin_cos, turned_sin_cos


def test_sin_cos_match_the_trig_functions_over_many_turns() -> None:
    """Within 3e-16 of NumPy's sine and cosine, at random angles over ±100 turns and at the
    multiples of π/2, where the half-angle tangent is largest or the cosine is 0."""
    rng = np.random.default_rng(7)
    angles = np.concatenate(
        [rng.uniform(-200 * np.pi, 200 * np.pi, 100_000), np.arange(-40, 41) * (np.pi / 2)]
    )
    sin, cos = sin_cos(angles)
    np.testing.assert_allclose(sin, np.sin(angles), rtol=0, atol=3e-16)
    np.testing.assert_allclose(cos, np.cos(angles), rtol=0, atol=3e-16)
    assert np.all(np.isfinite(sin)) and np.all(np.isfinite(cos))


def test_sin_cos_of_small_angles_keep_their_relative_precision() -> None:
    """Near 0 the sine is the angle to rounding (no cancellation), and NaN stays NaN."""
    tiny = np.array([1e-300, -1e-12, 1e-8, 0.0])
    sin, cos = sin_cos(tiny)
    np.testing.assert_allclose(sin, np.sin(tiny), rtol=1e-15, atol=0)
    np.testing.assert_array_equal(cos[[0, 3]], [1.0, 1.0])
    nan_sin, nan_cos = sin_cos(np.array([np.nan]))
    assert np.isnan(nan_sin[0]) and np.isnan(nan_cos[0])


@pytest.mark.skipif(
    np.finfo(np.longdouble).eps == np.finfo(np.float64).eps,
    reason="the exact sum needs a long double wider than float64",
)
@pytest.mark.parametrize("reach", [1e-9, 1e-5, 3e-3, TURN_REACH, 0.5])
def test_turned_sin_cos_match_the_trig_functions_of_the_sum(reach: float) -> None:
    """The sine and cosine of a + d from those of a (each series length the largest |d|
    needs, and beyond the reach the trig functions) within 2.5e-16 of the exact sine and
    cosine of the sum, at random angles a over ±10 turns and turns |d| ≤ ``reach``."""
    rng = np.random.default_rng(11)
    a = rng.uniform(-20 * np.pi, 20 * np.pi, 50_000)
    d = rng.uniform(-reach, reach, a.size)
    sin, cos = turned_sin_cos(np.sin(a), np.cos(a), d, a + d)
    exact = np.longdouble(a) + np.longdouble(d)  # the sum before its rounding to float64
    if reach > TURN_REACH:  # the trig functions of the rounded sum
        exact = np.longdouble(a + d)
    np.testing.assert_allclose(sin, np.sin(exact), rtol=0, atol=2.5e-16)
    np.testing.assert_allclose(cos, np.cos(exact), rtol=0, atol=2.5e-16)


def test_turned_sin_cos_by_nothing_are_the_given_values() -> None:
    """A zero turn leaves the sine and cosine as given, to the bit; NaN turns give NaN."""
    a = np.linspace(-3.0, 3.0, 7)
    sin, cos = turned_sin_cos(np.sin(a), np.cos(a), np.zeros(a.size), a)
    np.testing.assert_array_equal(sin, np.sin(a))
    np.testing.assert_array_equal(cos, np.cos(a))
    nan_sin, _ = turned_sin_cos(np.sin(a), np.cos(a), np.full(a.size, np.nan), a * np.nan)
    assert np.all(np.isnan(nan_sin))
