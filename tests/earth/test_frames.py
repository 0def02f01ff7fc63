"""Canonical-frame helpers: the half-angle sine and cosine."""

from __future__ import annotations

import numpy as np

from pipeline.earth.frames import sin_cos


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
