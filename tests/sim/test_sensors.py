"""Sensor error models: each error term, switched on alone, shows up with its configured size."""

from __future__ import annotations

import allantools
import numpy as np
import pytest
from numpy.typing import NDArray
from pydantic import ValidationError

from pipeline.earth.gravity import STANDARD_GRAVITY
from pipeline.sim.sensors import (
    PRESETS,
    AccelerometerErrors,
    GyroErrors,
    MagnetometerErrors,
    OdometerErrors,
    ToolSensors,
    TriadErrors,
    measure,
    odometer_md,
    tool_preset,
)

Floats = NDArray[np.float64]
FS = 100.0  # Hz
N_LONG = 200_000  # 2000 s at 100 Hz


def times(n: int, fs: float = FS, start: float = 0.0) -> Floats:
    return start + np.arange(n) / fs


def rng(seed: int = 7) -> np.random.Generator:
    return np.random.default_rng(seed)


def errors_only(errors: GyroErrors | AccelerometerErrors | MagnetometerErrors, n: int) -> Floats:
    """Measured minus ideal for a zero ideal signal, at FS."""
    return measure(np.zeros((n, 3)), errors, times(n), rng())


def adev_1s(data: Floats) -> float:
    _, dev, _, _ = allantools.oadev(data, rate=FS, data_type="freq", taus=[1.0])
    return float(dev[0])


# --- white noise ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("errors", "adev_per_density"),
    [
        (GyroErrors(noise_density=(0.15, 0.003, 1.0)), 60.0),  # deg/√h → deg/h at 1 s
        (AccelerometerErrors(noise_density=(0.006, 0.05, 0.3)), 1.0 / 60.0),  # (m/s)/√h → m/s²
        (MagnetometerErrors(noise_density=(0.1, 2.0, 30.0)), 1.0),  # nT/√Hz → nT
    ],
    ids=["gyro-arw", "accel-vrw", "magnetometer"],
)
def test_white_noise_allan_deviation_at_one_second(
    errors: TriadErrors, adev_per_density: float
) -> None:
    noise = errors_only(errors, N_LONG)  # type: ignore[arg-type]
    for axis, density in enumerate(np.broadcast_to(errors.noise_density, (3,))):
        assert adev_1s(noise[:, axis]) == pytest.approx(adev_per_density * density, rel=0.05)


def test_noise_density_scalar_applies_to_every_axis() -> None:
    noise = errors_only(GyroErrors(noise_density=0.1), 50_000)
    # per-sample σ = 60·N/√dt deg/h
    np.testing.assert_allclose(noise.std(axis=0), 60.0 * 0.1 / np.sqrt(1 / FS), rtol=0.02)


# --- deterministic terms -------------------------------------------------------------------


def test_constant_bias_is_exact() -> None:
    bias = (3.0, -2.5, 0.125)
    out = errors_only(AccelerometerErrors(bias=bias), 1000)
    np.testing.assert_array_equal(out, np.broadcast_to(bias, out.shape))


def test_bias_trend_slope_per_hour() -> None:
    trend = (0.5, -1.0, 2.0)  # deg/h per hour
    t = times(36_000, fs=10.0, start=120.0)  # one hour from t = 120 s
    out = measure(np.zeros((t.size, 3)), GyroErrors(bias_trend=trend), t, rng())
    slope_per_hour = np.polyfit(t / 3600.0, out, 1)[0]
    np.testing.assert_allclose(slope_per_hour, trend, rtol=1e-9)
    np.testing.assert_allclose(out, np.outer(t / 3600.0, trend), rtol=1e-12, atol=1e-15)


def test_scale_factor_and_misalignment_are_linear_gain() -> None:
    scale = (500.0, -300.0, 1200.0)  # ppm
    mis = ((0.0, 1.5, -2.0), (0.7, 0.0, 3.0), (-1.1, 0.4, 0.0))  # mrad
    true = rng(1).normal(scale=1e4, size=(500, 3))
    out = measure(true, MagnetometerErrors(scale_factor=scale, misalignment=mis), times(500), rng())
    gain = np.eye(3) + np.diag(np.array(scale) * 1e-6) + np.array(mis) * 1e-3
    np.testing.assert_allclose(out, true @ gain.T, rtol=1e-14, atol=1e-9)
    # row i, column j: sensor axis i sees the true component along j
    unit_y = measure(
        np.tile([0.0, 1.0, 0.0], (2, 1)), GyroErrors(misalignment=mis), times(2), rng()
    )
    np.testing.assert_allclose(unit_y[0], [1.5e-3, 1.0, 0.4e-3], rtol=1e-12)


def test_g_sensitivity_is_k_times_force_in_g() -> None:
    k = ((0.2, 1.0, -0.1), (-1.0, 0.3, 0.05), (0.0, 0.1, 0.4))  # (deg/h)/g
    force = rng(2).normal(scale=STANDARD_GRAVITY, size=(300, 3))
    out = measure(
        np.zeros((300, 3)), GyroErrors(g_sensitivity=k), times(300), rng(), specific_force=force
    )
    np.testing.assert_allclose(out, force @ np.array(k).T / STANDARD_GRAVITY, rtol=1e-13)
    at_rest = measure(
        np.zeros((2, 3)),
        GyroErrors(g_sensitivity=k),
        times(2),
        rng(),
        specific_force=np.tile([0.0, 0.0, STANDARD_GRAVITY], (2, 1)),
    )
    np.testing.assert_allclose(at_rest[0], [-0.1, 0.05, 0.4], rtol=1e-14)


def test_ideal_tool_measures_exactly_the_ideal_signals() -> None:
    tool = PRESETS["ideal"]
    assert tool.magnetometer is not None
    ideal = rng(3).normal(scale=50.0, size=(1000, 3))
    force = rng(4).normal(scale=9.8, size=(1000, 3))
    t = times(1000)
    for errors in (tool.gyro, tool.accelerometer, tool.magnetometer):
        force_in = force if isinstance(errors, GyroErrors) else None
        out = measure(ideal, errors, t, rng(), specific_force=force_in)
        np.testing.assert_array_equal(out, ideal)
    md = np.linspace(0.0, 3000.0, 101)
    np.testing.assert_array_equal(odometer_md(md, tool.odometer, rng()), md)


def test_measure_does_not_modify_its_input() -> None:
    ideal = np.ones((10, 3))
    measure(ideal, PRESETS["nav-grade"].gyro, times(10), rng())
    np.testing.assert_array_equal(ideal, 1.0)


# --- Gauss–Markov bias ---------------------------------------------------------------------


def test_gauss_markov_std_and_correlation_time() -> None:
    sigma, tau = (2.0, 0.5, 8.0), 0.3  # deg/h, s: ~6700 correlation times in the record
    out = errors_only(GyroErrors(bias_instability=sigma, correlation_time=tau), N_LONG)
    np.testing.assert_allclose(out.std(axis=0), sigma, rtol=0.05)
    lag = int(tau * FS)
    for axis in range(3):
        x = out[:, axis] - out[:, axis].mean()
        rho = np.dot(x[:-lag], x[lag:]) / np.dot(x, x)
        assert rho == pytest.approx(np.exp(-1.0), abs=0.04)


def test_gauss_markov_starts_stationary() -> None:
    errors = AccelerometerErrors(bias_instability=0.01, correlation_time=1e4)
    first = np.array([measure(np.zeros((2, 3)), errors, times(2), rng(s))[0] for s in range(600)])
    assert first.std() == pytest.approx(0.01, rel=0.07)


# --- odometer ------------------------------------------------------------------------------


def test_odometer_scale_exact() -> None:
    md = np.linspace(100.0, 3100.0, 301)
    out = odometer_md(md, OdometerErrors(scale_factor=800.0), rng())
    np.testing.assert_allclose(out, md * (1 + 800e-6), rtol=1e-15)


def test_odometer_noise_std() -> None:
    md = np.full(100_000, 1500.0)
    out = odometer_md(md, OdometerErrors(noise=0.05), rng())
    assert (out - md).std() == pytest.approx(0.05, rel=0.05)
    assert out.shape == md.shape


# --- reproducibility -----------------------------------------------------------------------


def test_same_seed_same_output_other_seed_differs() -> None:
    tool = PRESETS["mems-vrg"]
    n = 5000
    ideal, force = np.zeros((n, 3)), np.tile([0.0, 0.0, STANDARD_GRAVITY], (n, 1))
    a = measure(ideal, tool.gyro, times(n), rng(11), specific_force=force)
    b = measure(ideal, tool.gyro, times(n), rng(11), specific_force=force)
    c = measure(ideal, tool.gyro, times(n), rng(12), specific_force=force)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    md = np.linspace(0.0, 1000.0, n)
    np.testing.assert_array_equal(
        odometer_md(md, tool.odometer, rng(5)), odometer_md(md, tool.odometer, rng(5))
    )
    assert not np.array_equal(
        odometer_md(md, tool.odometer, rng(5)), odometer_md(md, tool.odometer, rng(6))
    )


def test_noise_realisation_does_not_depend_on_other_terms() -> None:
    noisy = GyroErrors(noise_density=0.1, bias_instability=0.5)
    with_bias = noisy.model_copy(update={"bias": (1.0, 2.0, 3.0)})
    np.testing.assert_allclose(
        errors_only(with_bias, 1000) - errors_only(noisy, 1000), np.tile([1.0, 2.0, 3.0], (1000, 1))
    )


# --- input checks --------------------------------------------------------------------------


def test_non_uniform_time_raises() -> None:
    t = times(100)
    t[50] += 0.003
    with pytest.raises(ValueError, match="uniformly sampled"):
        measure(np.zeros((100, 3)), GyroErrors(), t, rng())
    with pytest.raises(ValueError, match="uniformly sampled"):
        measure(np.zeros((100, 3)), GyroErrors(), times(100)[::-1], rng())


@pytest.mark.parametrize(
    ("ideal", "t", "message"),
    [
        (np.zeros((10, 2)), times(10), r"ideal must have shape \(n, 3\)"),
        (np.zeros((10, 3)), times(9), r"time must have shape \(10,\)"),
        (np.zeros((1, 3)), times(1), "at least 2 samples"),
    ],
)
def test_bad_shapes_raise(ideal: Floats, t: Floats, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        measure(ideal, GyroErrors(), t, rng())


def test_specific_force_rules() -> None:
    with pytest.raises(ValueError, match="pass specific_force"):
        measure(np.zeros((5, 3)), PRESETS["dtg-xy"].gyro, times(5), rng())
    with pytest.raises(ValueError, match="gyro errors only"):
        measure(
            np.zeros((5, 3)), AccelerometerErrors(), times(5), rng(), specific_force=np.ones((5, 3))
        )
    with pytest.raises(ValueError, match=r"specific_force must have shape \(5, 3\)"):
        measure(np.zeros((5, 3)), GyroErrors(), times(5), rng(), specific_force=np.ones((4, 3)))


def test_bare_triad_errors_refused() -> None:
    with pytest.raises(TypeError, match="noise-density unit depends on the sensor"):
        measure(np.zeros((5, 3)), TriadErrors(), times(5), rng())


# --- models and presets --------------------------------------------------------------------


def test_presets_validate_and_are_named_by_their_key() -> None:
    assert {"mems-vrg", "nav-grade", "dtg-xy", "ideal"} <= PRESETS.keys()
    for key, tool in PRESETS.items():
        assert ToolSensors.model_validate(tool.model_dump()) == tool
        assert tool.name == key
        assert tool.description
    assert PRESETS["mems-vrg"].gyro_axes == "x"
    assert PRESETS["mems-vrg"].magnetometer is None
    assert PRESETS["dtg-xy"].gyro_axes == "xy"
    assert PRESETS["ideal"].gyro_axes == "xyz"


def test_paper_preset_holds_only_the_papers_error_set() -> None:
    """mems-vrg-paper: gyro constant error (1σ-sized, 0.1 °/h 3σ), accelerometer constant
    error (4.4e-4 g 3σ) and accelerometer noise of 10 arc-min per 100 Hz sample; nothing
    else. The noise is checked on measured samples of a tool at rest."""
    tool = PRESETS["mems-vrg-paper"]
    assert tool.gyro_axes == "x" and tool.sample_rate == 100.0
    assert tool.gyro.model_dump(exclude={"bias"}) == GyroErrors().model_dump(exclude={"bias"})
    assert np.allclose(np.abs(tool.gyro.bias), 0.1 / 3, rtol=0.01)
    acc = tool.accelerometer
    assert acc.model_dump(exclude={"bias", "noise_density"}) == AccelerometerErrors().model_dump(
        exclude={"bias", "noise_density"}
    )
    assert np.allclose(np.abs(acc.bias), 4.4e-4 / 3 * STANDARD_GRAVITY, rtol=0.01)
    assert tool.odometer.scale_factor == 0.0 and tool.odometer.noise == 0.0
    n = 20_000
    still = np.tile([0.0, 0.0, STANDARD_GRAVITY], (n, 1))
    measured = measure(still, acc, np.arange(n) / 100.0, rng()) - np.asarray(acc.bias)
    tilt = np.degrees(np.arctan2(measured[:, 0], measured[:, 2])) * 60.0  # arc-min
    assert abs(np.std(tilt) - 10.0) < 0.15


def test_tool_preset_deep_merges_overrides() -> None:
    tool = tool_preset("mems-vrg", gyro={"bias": (1, 2, 3)}, sample_rate=50)
    base = PRESETS["mems-vrg"]
    assert tool.gyro.bias == (1.0, 2.0, 3.0)
    assert tool.gyro.model_dump(exclude={"bias"}) == base.gyro.model_dump(exclude={"bias"})
    assert tool.accelerometer == base.accelerometer
    assert tool.sample_rate == 50.0
    assert base.gyro.bias == (5.0, 5.0, 5.0)  # the preset itself is untouched
    with_mag = tool_preset("mems-vrg", magnetometer={"bias": (10, 0, 0)})
    assert with_mag.magnetometer == MagnetometerErrors(bias=(10, 0, 0))


def test_tool_preset_unknown_name_lists_presets() -> None:
    with pytest.raises(ValueError, match="unknown tool preset 'fog'") as info:
        tool_preset("fog")
    for name in PRESETS:
        assert name in str(info.value)


@pytest.mark.parametrize(
    ("overrides", "loc"),
    [
        ({"gyro": {"bais": 1.0}}, ("gyro", "bais")),
        ({"gyro": {"noise_density": -0.1}}, ("gyro", "noise_density")),
        (
            {"accelerometer": {"bias_instability": (0, -1, 0)}},
            ("accelerometer", "bias_instability"),
        ),
        ({"gyro": {"correlation_time": 0.0}}, ("gyro", "correlation_time")),
        ({"accelerometer": {"correlation_time": -5.0}}, ("accelerometer", "correlation_time")),
        ({"sample_rate": 0.0}, ("sample_rate",)),
        ({"odometer": {"noise": -1.0}}, ("odometer", "noise")),
        ({"gyro": {"bias": (1.0, float("nan"), 0.0)}}, ("gyro", "bias", 1)),
        ({"gyro_axes": "z"}, ("gyro_axes",)),
    ],
)
def test_bad_override_names_the_field(
    overrides: dict[str, object], loc: tuple[object, ...]
) -> None:
    with pytest.raises(ValidationError) as info:
        tool_preset("nav-grade", **overrides)
    assert [e["loc"][: len(loc)] for e in info.value.errors()] == [loc]


def test_misalignment_diagonal_refused() -> None:
    with pytest.raises(ValidationError, match="diagonal must be zero"):
        GyroErrors(misalignment=((0.1, 0, 0), (0, 0, 0), (0, 0, 0)))
