"""Predicted continuous-mode azimuth and inclination errors against closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.integrate import quad
from scipy.signal import savgol_filter

from pipeline.continuous.sigma import (
    AccelErrors,
    GyroNoise,
    InclinationNoise,
    RunGeometry,
    azimuth_budget,
    inclination_sigma,
)
from pipeline.continuous.sigma_forms import StationRows, markov_kernel

FloatArray = NDArray[np.float64]
T = 400.0  # s
INC = np.radians(30.0)
RAD_S = np.pi / 180.0 / 3600.0  # °/h → rad/s


def _run(inc: FloatArray, *, closure: bool = True, backward: bool = False) -> RunGeometry:
    t = np.linspace(0.0, T, inc.size)
    # azimuth north and gyro on the high side: no heading feedback (Φ = 1)
    return RunGeometry(
        time=t,
        inc=inc,
        azi=np.zeros_like(t),
        misalignment=np.zeros_like(t),
        usable=np.ones(t.size, dtype=bool),
        latitude=0.0,
        closure=closure,
        backward=backward,
    )


STATIONS = np.linspace(0.0, T, 9)
W = STATIONS / T


def test_stop_errors_mix_linearly_in_time() -> None:
    b = azimuth_budget(_run(np.full(2001, INC)), STATIONS, 0.01, 0.02, GyroNoise())
    np.testing.assert_allclose(b.sigma**2, ((1 - W) * 0.01) ** 2 + (W * 0.02) ** 2, rtol=1e-12)
    cov01 = (1 - W[2]) * (1 - W[5]) * 1e-4 + W[2] * W[5] * 4e-4
    assert b.covariance[2, 5] == pytest.approx(cov01, rel=1e-12)


def test_angle_random_walk_after_closure() -> None:
    """N²[S(t) − 2w S(t) + w² S(T)], S(t) = t/sin²I at constant inclination."""
    n = 0.05  # deg/√h
    b = azimuth_budget(_run(np.full(2001, INC)), STATIONS, 0.0, 0.0, GyroNoise(arw=n))
    arw = np.radians(n) / 60.0  # rad/√s
    s = STATIONS / np.sin(INC) ** 2
    expected = arw**2 * (s - 2 * W * s + W**2 * s[-1])
    np.testing.assert_allclose(b.parts["arw"], expected, rtol=1e-9, atol=1e-20)


def test_constant_bias_is_removed_only_at_constant_inclination() -> None:
    const = azimuth_budget(_run(np.full(2001, INC)), STATIONS, 0.0, 0.0, GyroNoise(bias=1.0))
    assert np.abs(const.parts["bias"]).max() < 1e-24
    # inclination from 10° to 60° linearly in time: residual b·[G(t) − w G(T)]
    inc0, inc1 = np.radians(10.0), np.radians(60.0)
    ramp = np.linspace(inc0, inc1, 20001)
    varying = azimuth_budget(_run(ramp), STATIONS, 0.0, 0.0, GyroNoise(bias=1.0))

    def g(t: float) -> float:
        return float(quad(lambda s: 1.0 / np.sin(inc0 + (inc1 - inc0) * s / T), 0.0, t)[0])

    big_g = np.array([g(t) for t in STATIONS])
    expected = (RAD_S * (big_g - W * big_g[-1])) ** 2
    np.testing.assert_allclose(varying.parts["bias"], expected, rtol=1e-6, atol=1e-20)


def test_rate_random_walk_after_closure() -> None:
    """Bias q·W(s): Var ∫₀ᵗW = t³/3, Cov(∫₀ᵗW, ∫₀ᵀW) = t²T/2 − t³/6."""
    q = 1.0  # (deg/h)/√h
    b = azimuth_budget(_run(np.full(4001, INC)), STATIONS, 0.0, 0.0, GyroNoise(rate_random_walk=q))
    qs = q * RAD_S / 60.0
    t = STATIONS
    var = t**3 / 3 - 2 * W * (t**2 * T / 2 - t**3 / 6) + W**2 * T**3 / 3
    np.testing.assert_allclose(
        b.parts["rate_random_walk"], qs**2 * var / np.sin(INC) ** 2, rtol=2e-3, atol=1e-20
    )


def test_bias_instability_without_closure() -> None:
    """Gauss–Markov bias σ, τ: Var ∫₀ᵗ = 2σ²τ²(t/τ − 1 + e^(−t/τ))."""
    tau = 60.0
    gyro = GyroNoise(bias_instability=0.5, correlation_time=tau)
    b = azimuth_budget(_run(np.full(4001, INC), closure=False), STATIONS, 0.0, 0.0, gyro)
    x = STATIONS / tau
    expected = 2 * (0.5 * RAD_S) ** 2 * tau**2 * (x - 1 + np.exp(-x)) / np.sin(INC) ** 2
    np.testing.assert_allclose(b.parts["bias_instability"], expected, rtol=2e-3, atol=1e-20)


def test_backward_run_grows_from_the_end_stop() -> None:
    n = 0.05
    run = _run(np.full(2001, INC), backward=True)
    b = azimuth_budget(run, STATIONS, 5.0, 0.01, GyroNoise(arw=n))  # start stop not used
    arw = np.radians(n) / 60.0
    expected = 0.01**2 + arw**2 * (T - STATIONS) / np.sin(INC) ** 2
    np.testing.assert_allclose(b.sigma**2, expected, rtol=1e-9)


def test_toolface_error_integrates_to_the_inclination_change() -> None:
    """A twist m of the accelerometer triad biases δ by m; h takes −İ·m, so without closure
    the azimuth error is m·∫İ/sin I dt = m·ln(tan(I/2)) between the ends (Earth rate
    negligible against İ here)."""
    inc0, inc1 = np.radians(10.0), np.radians(60.0)
    ramp = np.linspace(inc0, inc1, 20001)
    accel = AccelErrors(misalignment=1e-3)
    b = azimuth_budget(_run(ramp, closure=False), STATIONS, 0.0, 0.0, GyroNoise(), accel)
    inc_t = inc0 + (inc1 - inc0) * STATIONS / T
    expected = (1e-3 * np.log(np.tan(inc_t / 2) / np.tan(inc0 / 2))) ** 2
    np.testing.assert_allclose(b.parts["acc_twist_toolface"], expected, rtol=2e-3)


def test_inclination_sigma_matches_filtered_noise() -> None:
    """σ of the odometer noise through the integration's second-derivative fit, by
    simulation of the filter itself."""
    dt, points, sigma_odo = 0.01, 201, 0.05
    noise = InclinationNoise(
        dt=dt, accel=0.0, odometer=sigma_odo, odometer_points=points, inc_rate_points=None
    )
    predicted = inclination_sigma(np.array([np.pi / 2]), noise, AccelErrors())[0]
    rng = np.random.default_rng(3)
    accel = savgol_filter(rng.normal(0.0, sigma_odo, 400_000), points, 3, deriv=2, delta=dt)
    measured = np.std(accel[points:-points]) / noise.gravity  # δI = sin I·δa/g at I = 90°
    assert measured == pytest.approx(predicted, rel=0.02)


@pytest.mark.skipif(
    np.finfo(np.longdouble).eps == np.finfo(np.float64).eps,
    reason="the reference needs a long double wider than float64",
)
@pytest.mark.parametrize("closed", [True, False], ids=["closure", "free"])
def test_station_rows_forms_equal_the_explicit_matrices_near_the_closing_stop(
    closed: bool,
) -> None:
    """The rows' products and forms (linear, ARW's diagonal, the Markov kernel's quadratic)
    against the (stations, cells) matrix a[k, j] = Φ_k − c_k before station k, −c_k after,
    multiplied out in long double: within 1e-15 of each form's largest entry, and each
    station's variance within 5e-15 relative (1e-12 for the kernel's) — also a cell before
    the closing stop, where Φ_k ≈ c_k, and where sums of the whole less those before a
    station cancelled to 2e-13, 1e-13 and 5e-11 of its variance."""
    rng = np.random.default_rng(5)
    cells = 700
    mid = np.sort(rng.uniform(0.0, 1000.0, cells))
    g, d = rng.normal(1.0, 0.3, cells), rng.uniform(0.5, 1.5, cells)
    before = np.array([0, 3, 100, 350, 350, 690, 699, 700])
    phi_t = 2.0
    phi = phi_t * before / cells + rng.normal(0.0, 1e-3, before.size)
    phi[-1] = phi_t
    closure = phi_t * before / cells if closed else np.zeros(before.size)
    rows = StationRows(phi, closure, before, cells)
    wide = np.longdouble
    a = np.zeros((before.size, cells), dtype=wide)
    for k, n in enumerate(before):
        a[k, :n] = wide(phi[k]) - wide(closure[k])
        a[k, n:] = -wide(closure[k])
    kernel = np.exp(-np.abs(mid[:, None].astype(wide) - mid[None, :].astype(wide)) / wide(50.0))
    gw = g.astype(wide)
    cases = [
        (rows.linear(g), a @ gw, 5e-15),
        (rows.diagonal(d), (a * d.astype(wide)) @ a.T, 5e-15),
        (
            rows.quadratic(g, mid, markov_kernel(50.0)),
            a @ (gw[:, None] * kernel * gw) @ a.T,
            1e-12,
        ),
    ]
    for got, want, bound in cases:
        want = np.asarray(want)
        assert np.abs(got - want).max() <= 1e-15 * np.abs(want).max()
        variance = (np.diag(got), np.diag(want)) if want.ndim == 2 else (got, want)
        error = np.abs(variance[0] - variance[1])
        assert (error <= bound * np.abs(variance[1])).all()


@pytest.mark.skipif(
    np.finfo(np.longdouble).eps == np.finfo(np.float64).eps,
    reason="the reference needs a long double wider than float64",
)
@pytest.mark.parametrize("reverse", [False, True], ids=["forward", "reverse"])
def test_markov_kernel_sums_over_many_correlation_times(reverse: bool) -> None:
    """The Gauss–Markov kernel's sums before each pair of cuts (its semi-separable form)
    against the explicit kernel summed in long double, over 150 correlation times (several
    of its segments, gaps of 40 τ between cells among them), cuts unsorted and repeated,
    cells in reverse time order as for the sums after the stations: within 4e-15 of each
    entry."""
    rng = np.random.default_rng(11)
    tau = 20.0
    mid = np.sort(np.concatenate([rng.uniform(0.0, 1000.0, 300), rng.uniform(1800.0, 3000.0, 200)]))
    g = rng.uniform(0.2, 2.0, mid.size)
    at = np.array([500, 0, 3, 250, 250, 301, 499, 120, 0, 500])
    if reverse:
        mid, g = mid[::-1].copy(), g[::-1].copy()
    wide = np.longdouble
    kernel = np.exp(-np.abs(mid[:, None].astype(wide) - mid[None, :].astype(wide)) / wide(tau))
    terms = g.astype(wide)[:, None] * kernel * g.astype(wide)
    running = np.zeros((mid.size + 1, mid.size + 1), dtype=wide)
    running[1:, 1:] = terms.cumsum(axis=0).cumsum(axis=1)
    want = np.asarray(running[np.ix_(at, at)], dtype=np.float64)
    got = markov_kernel(tau).before_sums(g, mid, at)
    np.testing.assert_allclose(got, want, rtol=4e-15, atol=0.0)
