"""Two- and three-axis gyro tools in continuous mode against noise-free simulations.

The simulator is the forward model: it makes the body rates from the true attitude
(DOMAIN.md §2) and the integration must give the true azimuth and trajectory back."""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pyarrow as pa
import pytest
from continuous_support import LAT, SITE, azimuth_error, compassed, position_error
from scipy.spatial.transform import Rotation

from pipeline.continuous import (
    FLAG_AFTER_VERTICAL,
    FLAG_AZIMUTH_UNDEFINED,
    FLAG_NEAR_VERTICAL,
    ContinuousError,
    ContinuousOptions,
    integrate_continuous,
)
from pipeline.continuous.multiaxis import apsidal_components, resolve_gyro_axes
from pipeline.continuous.strapdown import close_attitude, propagate_attitude
from pipeline.earth.frames import OMEGA_EARTH, body_to_ned, earth_rate_ned, rot_z
from pipeline.sim.simulate import Simulation, simulate
from pipeline.sim.spec import SimulationSpec

BUILD_HOLD = {  # ~1 km logged from 160 m (I = 6°) to 1150 m
    "sections": [
        {"kind": "vertical", "length": 100},
        {"kind": "build", "dls": 3.0, "inc": 40, "azi": 60},
        {"kind": "curve", "dls": 2.0, "inc": 45, "azi": 100},
        {"kind": "hold", "to_md": 1150},
    ]
}
NEAR_VERTICAL = {  # from 12° down to 0.52° while the azimuth swings through 190°, then 30°
    "start_md": 100,
    "start_inc": 12,
    "start_azi": 60,
    "sections": [
        {"kind": "curve", "dls": 3.0, "inc": 4, "azi": 250},
        {"kind": "build", "dls": 3.0, "inc": 30},
        {"kind": "hold", "length": 500},
    ],
}
HOLD = {"start_inc": 40, "start_azi": 60, "sections": [{"kind": "hold", "length": 800}]}
SHORT = {
    "sections": [
        {"kind": "vertical", "length": 20},
        {"kind": "build", "dls": 6.0, "inc": 30, "azi": 60},
        {"kind": "hold", "length": 60},
    ]
}
OPTIONS = ContinuousOptions(spacing=5.0, odometer_window=0.07)


def rot_x(angle: np.ndarray) -> np.ndarray:
    """Rotation matrices about x, (n, 3, 3): [[1, 0, 0], [0, c, −s], [0, s, c]]."""
    matrices: np.ndarray = Rotation.from_rotvec(np.outer(angle, [1.0, 0.0, 0.0])).as_matrix()
    return matrices


def make_spec(
    well: dict[str, Any],
    axes: str,
    start_md: float,
    servo: bool = True,
    bias: tuple[float, float, float] | None = None,
    rate: float = 50.0,
) -> SimulationSpec:
    overrides: dict[str, Any] = {"gyro_axes": axes, "sample_rate": rate, "magnetometer": None}
    if bias is not None:
        overrides["gyro"] = {"bias": bias}
    return SimulationSpec.model_validate(
        {
            "name": "multiaxis",
            "seed": 4,
            "site": SITE,
            "well": well,
            "tool": {"preset": "ideal", "overrides": overrides},
            "survey": {
                "mode": "continuous",
                "start_md": start_md,
                "speed": 2.0,
                "ramp_time": 3.0,
                "stop": {"dwell": 3.0, "move_time": 1.0},
                "stabilisation": {"enabled": servo, "residual": 3.0, "correlation": 2.0},
            },
        }
    )


WELLS: dict[str, dict[str, Any]] = {
    "build_hold": BUILD_HOLD,
    "near_vertical": NEAR_VERTICAL,
    "hold": HOLD,
    "short": SHORT,
}


@cache
def simulated(
    well: str,
    axes: str,
    start_md: float,
    servo: bool = True,
    bias: tuple[float, float, float] | None = None,
    rate: float = 50.0,
) -> tuple[SimulationSpec, Simulation, pa.Table]:
    spec = make_spec(WELLS[well], axes, start_md, servo, bias, rate)
    sim = simulate(spec)
    _, stops, rejects = compassed(sim.samples)
    assert rejects.num_rows == 0
    return spec, sim, stops


@pytest.mark.parametrize("servo", [True, False], ids=["servo", "free_rotating"])
def test_two_axis_round_trip_build_and_hold(servo: bool) -> None:
    spec, sim, stops = simulated("build_hold", "xy", 160.0, servo)
    result = integrate_continuous(sim.samples, stops, LAT, OPTIONS)
    err, flags = azimuth_error(result, sim)
    assert np.all(flags == 0)
    assert np.abs(err).max() < 0.01
    assert abs(result.misclosure) < 0.01
    md = result.stations.column("md").to_numpy()
    assert md[-1] - md[0] > 980
    assert np.abs(position_error(result, spec)).max() < 0.01
    # the toolface really is free to turn (many turns) or held near the high side
    moving = sim.samples.column("station").is_null().to_numpy(zero_copy_only=False)
    tf = np.unwrap(np.radians(sim.truth.column("toolface").to_numpy()[moving]))
    turns = np.ptp(tf) / (2 * np.pi)
    assert turns < 0.2 if servo else turns > 5


@pytest.mark.parametrize(
    ("well", "start_md", "servo"),
    [("near_vertical", 110.0, True), ("build_hold", 50.0, False)],
    ids=["through_near_vertical", "from_vertical_stop"],
)
def test_three_axis_round_trip_through_vertical(well: str, start_md: float, servo: bool) -> None:
    """No ÷ sin I: the attitude is integrated through vertical with a closure on the end
    stop; only the azimuth itself is flagged where it is ill-defined."""
    # 100 Hz: the attitude errs by about jump·Δt/2 where the rate jumps (junctions of arcs),
    # the inclination from the accelerometers of x and xy tools does not
    spec, sim, stops = simulated(well, "xyz", start_md, servo, rate=100.0)
    result = integrate_continuous(sim.samples, stops, LAT, OPTIONS)
    err, flags = azimuth_error(result, sim)
    truth_inc = result.series.read_all().column("inc").to_numpy()
    near = truth_inc < OPTIONS.vertical_below
    assert near.sum() > 1000  # the run really spends time near vertical
    np.testing.assert_array_equal(flags, np.where(near, FLAG_AZIMUTH_UNDEFINED, 0))
    assert np.abs(err[flags == 0]).max() < 0.01
    assert abs(result.misclosure) < 0.01  # closed on the end stop, not integrated backward
    # positions need sin I·(cos A, sin A), which the attitude keeps through vertical
    assert np.abs(position_error(result, spec)).max() < 0.01
    stations = result.stations
    undefined = stations.column("flags").to_numpy() & FLAG_AZIMUTH_UNDEFINED > 0
    assert undefined.any()
    assert np.all(np.isinf(stations.column("sigma_azi").to_numpy()[undefined]))
    assert np.all(np.isfinite(stations.column("sigma_azi").to_numpy()[~undefined]))


def test_two_axis_near_vertical_is_held_and_flagged() -> None:
    _, sim, stops = simulated("near_vertical", "xy", 110.0)
    result = integrate_continuous(sim.samples, stops, LAT, OPTIONS)
    _, flags = azimuth_error(result, sim)
    held = flags & FLAG_NEAR_VERTICAL > 0
    after = flags & FLAG_AFTER_VERTICAL > 0
    first_held = int(np.argmax(held))
    assert held.sum() > 1000
    assert np.all(after[first_held:] | held[first_held:])
    # before the held section the integration is exact up to the closure, which here absorbs
    # the 190° swing the held section missed: the misclosure says so
    assert abs(result.misclosure) > 90
    raw = integrate_continuous(
        sim.samples, stops, LAT, OPTIONS.model_copy(update={"closure": False})
    )
    raw_err, _ = azimuth_error(raw, sim)
    assert np.abs(raw_err[:first_held]).max() < 0.01


@pytest.mark.parametrize(
    ("axes", "bias"), [("xy", (2.0, -1.5, 0.0)), ("xyz", (2.0, -1.5, 1.0))], ids=["xy", "xyz"]
)
def test_constant_gyro_bias_is_removed_by_the_closure(
    axes: str, bias: tuple[float, float, float]
) -> None:
    """Servo'd tool on a straight hold: a constant gyro bias tilts the azimuth linearly in
    time, as for the single-axis tool; the closure on the end stop removes it."""
    _, sim, stops = simulated("hold", axes, 20.0, True, bias)
    raw = integrate_continuous(
        sim.samples, stops, LAT, OPTIONS.model_copy(update={"closure": False})
    )
    closed = integrate_continuous(sim.samples, stops, LAT, OPTIONS)
    err_raw, _ = azimuth_error(raw, sim)
    t = raw.series.read_all().column("time").to_numpy()
    linear = np.polyval(np.polyfit(t, err_raw, 1), t)
    assert np.abs(err_raw).max() > 0.1
    assert np.abs(err_raw - linear).max() < 0.1 * np.abs(err_raw).max()
    assert raw.misclosure == pytest.approx(err_raw[-1], abs=0.01)
    err_closed, _ = azimuth_error(closed, sim)
    assert np.abs(err_closed).max() < 0.1 * np.abs(err_raw).max()


def test_dispatch_by_gyro_columns_and_option() -> None:
    _, sim, stops = simulated("short", "xyz", 50.0)
    samples = sim.samples
    x_only = samples.drop_columns(["gyro_y", "gyro_z"])
    xy_only = samples.drop_columns(["gyro_z"])

    def series(table: pa.Table, axes: str) -> np.ndarray:
        options = OPTIONS.model_copy(update={"gyro_axes": axes})
        result = integrate_continuous(table, stops, LAT, options)
        err, flags = azimuth_error(result, sim)
        assert np.all(flags == 0) and np.abs(err).max() < 0.01  # every method is exact
        return np.stack([result.series.read_all().column(n).to_numpy() for n in ("inc", "azi")])

    # an explicit choice uses only those axes; auto takes every gyro column present
    chosen = {axes: series(samples, axes) for axes in ("x", "xy", "xyz")}
    np.testing.assert_array_equal(chosen["x"], series(x_only, "auto"))
    np.testing.assert_array_equal(chosen["xy"], series(xy_only, "auto"))
    np.testing.assert_array_equal(chosen["xyz"], series(samples, "auto"))
    assert not np.array_equal(chosen["x"], chosen["xy"])  # different methods
    assert not np.array_equal(chosen["xy"], chosen["xyz"])
    with pytest.raises(ContinuousError, match="gyro_z"):
        integrate_continuous(xy_only, stops, LAT, OPTIONS.model_copy(update={"gyro_axes": "xyz"}))


def test_resolve_gyro_axes() -> None:
    assert resolve_gyro_axes(["time", "gyro_x", "acc_x"], "auto") == "x"
    assert resolve_gyro_axes(["gyro_x", "gyro_y"], "auto") == "xy"
    assert resolve_gyro_axes(["gyro_x", "gyro_y", "gyro_z"], "auto") == "xyz"
    assert resolve_gyro_axes(["gyro_x", "gyro_y", "gyro_z"], "x") == "x"
    with pytest.raises(ContinuousError, match=r"no gyro_y column \(gyro columns present: gyro_x"):
        resolve_gyro_axes(["gyro_x"], "xy")


def test_three_axis_without_position_markers() -> None:
    """Without frame-position markers an inclined stop is tied at its last sample (I, ψ from
    the accelerometers); a near-vertical one cannot be, and says why."""
    _, sim, stops = simulated("build_hold", "xyz", 160.0)
    result = integrate_continuous(sim.samples.drop_columns(["position"]), stops, LAT, OPTIONS)
    err, flags = azimuth_error(result, sim)
    assert np.all(flags == 0)
    assert np.abs(err).max() < 0.01
    _, vertical, vertical_stops = simulated("build_hold", "xyz", 50.0, False)
    with pytest.raises(ContinuousError, match=r"stop 0 is near vertical .*'position'"):
        integrate_continuous(
            vertical.samples.drop_columns(["position"]), vertical_stops, LAT, OPTIONS
        )


def test_apsidal_components_of_the_earth_rate() -> None:
    """At rest h and r are DOMAIN.md §5's Earth-rate components at any roll ψ."""
    azi, inc = np.radians(130.0), np.radians(35.0)
    psi = np.radians(np.arange(0.0, 360.0, 15.0))
    rate = np.einsum("nji,j->ni", body_to_ned(azi, inc, psi), earth_rate_ned(np.radians(LAT)))
    high, right = apsidal_components(rate[:, 0], rate[:, 1], psi)
    oc, os_ = OMEGA_EARTH * np.cos(np.radians(LAT)), OMEGA_EARTH * np.sin(np.radians(LAT))
    np.testing.assert_allclose(high, oc * np.cos(azi) * np.cos(inc) + os_ * np.sin(inc), atol=1e-18)
    np.testing.assert_allclose(right, -oc * np.sin(azi), atol=1e-18)


def test_strapdown_matches_an_analytic_non_commuting_motion() -> None:
    """A rotating, nutating body, C_b^n = Rz(a t)·Rx(b t) relative to the Earth-fixed NED
    frame: the gyros read ω_ib^b = (b, a sin bt, a cos bt) + C_n^b ω_ie^n."""
    a, b = 0.8, 0.5  # rad/s
    t = np.arange(0.0, 60.0, 0.01)
    earth = earth_rate_ned(np.radians(LAT))
    exact = rot_z(a * t) @ rot_x(b * t)
    rates = np.stack([np.full_like(t, b), a * np.sin(b * t), a * np.cos(b * t)], axis=-1)
    rates += np.einsum("nji,j->ni", exact, earth)
    attitude = propagate_attitude(t, rates, exact[0], earth)
    error = Rotation.from_matrix(np.einsum("nij,nkj->nik", attitude, exact)).magnitude()
    assert error.max() < 1e-8  # rad, after 6000 steps of up to 0.5° each


def test_closure_removes_a_drift_at_a_constant_rate() -> None:
    t = np.linspace(0.0, 500.0, 1001)
    truth = body_to_ned(np.radians(70.0), np.radians(35.0), np.radians(10.0)) @ rot_x(0.001 * t)
    drift = np.array([1e-6, -2e-6, 5e-6])  # rad/s in NED
    drifted = Rotation.from_rotvec(t[:, None] * drift[None, :]).as_matrix() @ truth
    closed = close_attitude(drifted, t, drift * (t[-1] - t[0]))
    np.testing.assert_allclose(closed, truth, atol=1e-14)
