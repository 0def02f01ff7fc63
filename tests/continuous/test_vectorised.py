"""The vectorised continuous stage against the per-sample implementation it replaced.

``tests/data/continuous/previous_outputs.json`` holds the outputs of the previous
implementation (commit ``generated_by``: the Heun step loop, and dense station rows in the
inclination-noise budget) for short simulated runs whose specs it carries: single-axis
forward, two-axis forward, and single-axis integrated back from the end stop across a held
near-vertical section (series every ``series_every`` samples, all stations), given the
compassed stops stored beside it (``stops-<case>.parquet``), so that a change in compassing
does not touch this comparison. The stage must reproduce them within 1e-8° (:data:`TOLERANCE`).
Should the simulator's samples change, compass each case's new samples again
(``continuous_support.compassed``) into its stops file, then regenerate the file by running
``integrate_continuous`` of commit ``generated_by`` (a detached git worktree on PYTHONPATH, in
an interpreter of its own) on each case's samples and stored stops with the file's options;
the file's ``notes`` say how it was last made. The two vectorised solvers are also checked
against the plain per-sample definitions written out here.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
from continuous_support import LAT
from numpy.typing import NDArray
from scipy.signal import savgol_coeffs

from pipeline.continuous import ContinuousOptions, integrate_continuous
from pipeline.continuous.integrate import _heun_series
from pipeline.continuous.sigma_noise import InclinationNoise, NoiseSums
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec

FloatArray = NDArray[np.float64]
REFERENCE = Path(__file__).parents[1] / "data" / "continuous" / "previous_outputs.json"
TOLERANCE = 1e-8  # deg
"""The previous outputs were stored from one CPU; on another, NumPy's vectorised sin/cos and
the simulator's samples round the last bit differently, and integration over thousands of
samples carries it (AVX-512: 1.3e-9° apart). 1e-8° ≈ 1.7e-10 rad is far below any survey
azimuth's resolution, and far above the last bit of a degree value (≈ 1e-14)."""


@cache
def reference() -> dict[str, Any]:
    data: dict[str, Any] = json.loads(REFERENCE.read_text())
    return data


@pytest.mark.parametrize(
    "case", ["single_axis_forward", "two_axis_forward", "single_axis_backward"]
)
def test_stage_reproduces_the_previous_implementation(case: str) -> None:
    ref = reference()
    expected = ref["cases"][case]
    sim = simulate(SimulationSpec.model_validate(expected["spec"]))
    assert sim.samples.num_rows == expected["samples"], "the simulator changed: regenerate"
    stops = pq.read_table(REFERENCE.parent / f"stops-{case.replace('_', '-')}.parquet")
    result = integrate_continuous(sim.samples, stops, LAT, ContinuousOptions(**ref["options"]))
    series = result.series.read_all()
    times = series.column("time").to_numpy()[:: ref["series_every"]]
    np.testing.assert_array_equal(times, expected["series"]["time"])
    for table, columns, every in (
        (series, ("azi", "inc"), ref["series_every"]),
        (result.stations, ("md", "azi", "inc", "sigma_azi", "sigma_inc"), 1),
    ):
        name = "series" if table is series else "stations"
        for column in columns:
            got = table.column(column).to_numpy()[::every]
            want = np.asarray(expected[name][column], dtype=np.float64)
            assert got.shape == want.shape
            finite = np.isfinite(want)
            assert np.array_equal(np.isfinite(got), finite), f"{name}.{column}"
            np.testing.assert_array_equal(got[~finite], want[~finite])
            diff = got[finite] - want[finite]
            if column == "azi":
                diff = (diff + 180.0) % 360.0 - 180.0
            assert np.abs(diff).max(initial=0.0) <= TOLERANCE, f"{name}.{column}"
    flags = result.stations.column("flags").to_numpy()
    np.testing.assert_array_equal(flags, expected["stations"]["flags"])
    if np.isnan(expected["misclosure"]):
        assert np.isnan(result.misclosure)
    else:
        assert result.misclosure == pytest.approx(expected["misclosure"], abs=TOLERANCE)
    if case == "single_axis_backward":  # the case crosses a held section
        assert np.any(flags & 1)


def _heun_loop(step: FloatArray, rate: Callable[[float, int], float], azi0: float) -> FloatArray:
    """The Heun recursion one step at a time."""
    azi = np.empty(step.size + 1)
    azi[0] = a = azi0
    f = rate(a, 0)
    for k, h in enumerate(step):
        f_next = rate(a + h * f, k + 1)
        a = a + h / 2 * (f + f_next)
        f = rate(a, k + 1)
        azi[k + 1] = a
    return azi


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_heun_series_matches_the_step_by_step_recursion(direction: float) -> None:
    """A strong, varying dependence on A (a low-inclination Earth-rate feedback 50× the real
    one over a long run), uneven steps, held samples, forward and back in time."""
    rng = np.random.default_rng(3)
    n = 20_000
    t = direction * np.cumsum(rng.uniform(0.05, 0.15, n))
    const = 2e-3 * np.sin(np.arange(n) / 900.0) + 1e-4 * rng.standard_normal(n)
    by_cos = 5e-3 * (1.0 + 0.5 * np.cos(np.arange(n) / 2000.0))
    by_sin = -2e-3 * np.ones(n)
    held = (np.arange(n) > 5000) & (np.arange(n) < 6000)
    const[held] = by_cos[held] = by_sin[held] = 0.0

    def rate(sin_a: FloatArray, cos_a: FloatArray, k: slice) -> tuple[FloatArray, FloatArray]:
        return (
            const[k] + by_cos[k] * cos_a + by_sin[k] * sin_a,
            by_sin[k] * cos_a - by_cos[k] * sin_a,
        )

    def scalar(a: float, k: int) -> float:
        return float(const[k] + by_cos[k] * np.cos(a) + by_sin[k] * np.sin(a))

    expected = _heun_loop(np.diff(t), scalar, 0.3)
    got = _heun_series(np.diff(t), rate, np.hypot(by_cos, by_sin), np.full(n, 0.3))
    assert np.ptp(expected) > 1.0  # the azimuth turns: the feedback matters
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def _kernel(points: int | None, order: int, deriv: int, dt: float) -> FloatArray:
    """Savitzky–Golay derivative kernel, or for None central differences (applied twice)."""
    if points is not None:
        out: FloatArray = savgol_coeffs(points, order, deriv=deriv, delta=dt)
        return out
    first = np.array([1.0, 0.0, -1.0]) / (2 * dt)
    return first if deriv == 1 else np.convolve(first, first)


def _dense_variance(
    noise: InclinationNoise,
    elapsed: FloatArray,
    st_elapsed: FloatArray,
    sample: dict[str, FloatArray],
    w: FloatArray,
) -> FloatArray:
    """Each station's full row over the samples, filtered by direct convolution."""
    d1 = _kernel(noise.inc_rate_points, 2, 1, noise.dt)[::-1]
    d2 = _kernel(noise.odometer_points, 3, 2, noise.dt)[::-1]
    phi = sample["transition"]
    out = []
    for s, te in enumerate(st_elapsed):
        before = np.arange(elapsed.size) < np.searchsorted(elapsed, te, side="left")
        row = (np.interp(te, elapsed, phi) * before - w[s] * phi[-1]) * sample["step"]
        q = row * sample["d_inc"] + np.convolve(row * sample["d_inc_rate"], d1, mode="same")
        odo = np.convolve(q * sample["sin_i"], d2, mode="same")
        out.append(
            (noise.accel / noise.gravity) ** 2 * q @ q
            + (noise.odometer / noise.gravity) ** 2 * odo @ odo
        )
    return np.array(out)


def _inclination_noise_variance(
    noise: InclinationNoise,
    elapsed: NDArray[np.float64],
    st_elapsed: NDArray[np.float64],
    step: NDArray[np.float64],
    transition: NDArray[np.float64],
    w: NDArray[np.float64],
    d_inc: NDArray[np.float64],
    d_inc_rate: NDArray[np.float64],
    sin_i: NDArray[np.float64],
    cells: int = 500_000,
) -> NDArray[np.float64]:
    """Variance at each station of the azimuth error the inclination's sample noise makes, by
    the stage's running sums (:class:`NoiseSums`) added in one block over whole per-sample
    arrays in integration order: ``step`` is the sample step divided by Φ (s), ``transition``
    Φ."""
    index = np.searchsorted(elapsed, st_elapsed, side="left")
    sums = NoiseSums(noise, elapsed.size, index, cells)
    sums.add(0, elapsed.size, 0, step, d_inc, d_inc_rate, sin_i)
    phi_t = float(transition[-1])
    return sums.variance(np.interp(st_elapsed, elapsed, transition) - w * phi_t, -w * phi_t)


@pytest.mark.parametrize("points", [(31, 61), (None, None)])
def test_inclination_noise_variance_matches_dense_rows(
    points: tuple[int | None, int | None],
) -> None:
    """Stations at the run's ends (filter windows past the samples) and in between, Φ ≠ 1."""
    rng = np.random.default_rng(5)
    n, dt = 3000, 0.01
    elapsed = np.arange(n) * dt
    transition = np.exp(0.05 * np.sin(elapsed))
    inner = np.sort(rng.uniform(0.0, elapsed[-1], 12))
    st_elapsed = np.concatenate([[0.0, 0.05], inner, [elapsed[-1] - 0.1, elapsed[-1]]])
    w = st_elapsed / elapsed[-1]
    sample = {
        "step": np.gradient(elapsed) / transition,
        "transition": transition,
        "d_inc": rng.normal(0.0, 1e-3, n),
        "d_inc_rate": rng.normal(0.0, 1e-2, n),
        "sin_i": np.sin(np.radians(20.0 + 10.0 * np.sin(elapsed / 7.0))),
    }
    noise = InclinationNoise(
        dt=dt, accel=1e-3, odometer=0.05, odometer_points=points[1], inc_rate_points=points[0]
    )
    got = _inclination_noise_variance(noise, elapsed, st_elapsed, w=w, cells=2000, **sample)
    expected = _dense_variance(noise, elapsed, st_elapsed, sample, w)
    assert expected[0] == 0.0  # at the tie: nothing integrated yet, w = 0
    assert np.all(expected[1:] > 0)
    np.testing.assert_allclose(got, expected, rtol=1e-11, atol=1e-24)
