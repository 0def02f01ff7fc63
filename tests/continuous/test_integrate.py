"""Continuous-mode integration against noise-free simulations (DOMAIN.md §6)."""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pytest
from continuous_support import LAT, SITE, azimuth_error, compassed, position_error

from pipeline.continuous import (
    FLAG_NEAR_VERTICAL,
    FLAG_NO_CLOSURE,
    ContinuousOptions,
    ContinuousResult,
    integrate_continuous,
)
from pipeline.sim.simulate import Simulation, simulate
from pipeline.sim.spec import SimulationSpec

MAGNETIC = {"total_field": 59731.0, "dip": 78.29, "declination": 17.0}
SECTIONS = [
    {"kind": "vertical", "length": 20},
    {"kind": "build", "dls": 6.0, "inc": 30, "azi": 60},
    {"kind": "curve", "dls": 4.0, "inc": 35, "azi": 100},
    {"kind": "hold", "length": 60},
]
SURVEY = {
    "mode": "continuous",
    "start_md": 130,
    "speed": 1.0,
    "ramp_time": 3.0,
    "stop": {"dwell": 3.0, "move_time": 1.0},
    "stabilisation": {"residual": 3.0, "correlation": 2.0},
}


def make_spec(tool: dict[str, Any], survey: dict[str, Any] | None = None) -> SimulationSpec:
    return SimulationSpec.model_validate(
        {
            "name": "t",
            "seed": 4,
            "site": {**SITE, "magnetic": MAGNETIC},
            "well": {"sections": SECTIONS},
            "tool": tool,
            "survey": survey or SURVEY,
        }
    )


@cache
def run(bias: float = 0.0) -> tuple[Simulation, pa.Table]:
    overrides: dict[str, Any] = {"gyro_axes": "x"}
    if bias:
        overrides["gyro"] = {"bias": (bias, 0.0, 0.0)}
    sim = simulate(make_spec({"preset": "ideal", "overrides": overrides}))
    _, stops, _ = compassed(sim.samples)
    return sim, stops


def integrate(bias: float = 0.0, closure: bool = True) -> ContinuousResult:
    sim, stops = run(bias)
    return integrate_continuous(
        sim.samples,
        stops,
        LAT,
        ContinuousOptions(spacing=5.0, closure=closure, odometer_window=0.07),
    )


def usable_azimuth_error(result: ContinuousResult, sim: Simulation) -> np.ndarray:
    """Integrated minus true azimuth (deg) where the hole is not near vertical."""
    err, flags = azimuth_error(result, sim)
    usable: np.ndarray = err[flags & FLAG_NEAR_VERTICAL == 0]
    return usable


def test_noise_free_run_recovers_azimuth_and_trajectory() -> None:
    sim, _ = run()
    result = integrate()
    err = usable_azimuth_error(result, sim)
    assert err.size > 1000
    assert np.abs(err).max() < 0.01
    assert abs(result.misclosure) < 0.01
    stations = result.stations
    md = stations.column("md").to_numpy()
    assert np.all(stations.column("flags").to_numpy() == 0)
    assert np.abs(position_error(result, make_spec({"preset": "ideal"}))).max() < 0.01
    assert md[0] == pytest.approx(130.0) and np.diff(md).max() <= 5.0 + 1e-9


def test_constant_gyro_bias_drifts_linearly_and_closure_removes_it() -> None:
    bias = 2.0  # deg/h on the gyro
    sim, _ = run(bias)
    raw = integrate(bias, closure=False)
    clean = integrate(bias, closure=True)
    err_raw = usable_azimuth_error(raw, sim)
    t = raw.series.read_all().column("time").to_numpy()
    t = t - t[0]
    slope, offset = np.polyfit(t, err_raw, 1)
    linear = slope * t + offset
    # the drift is linear in time (constant inclination ⇒ constant ∂Ȧ/∂h ≈ −1/sin I)
    assert np.abs(err_raw).max() > 0.05
    assert np.abs(err_raw - linear).max() < 0.1 * np.abs(err_raw).max()
    assert raw.misclosure == pytest.approx(err_raw[-1], abs=0.01)
    assert np.abs(usable_azimuth_error(clean, sim)).max() < 0.1 * np.abs(err_raw).max()


def test_stage_registers_and_runs() -> None:
    from types import SimpleNamespace

    from pipeline.stages.continuous import (
        ContinuousParams,
        continuous_stage,
        gyropipe_register_stages,
    )
    from pipeline.well import WellMetadata

    defs: list[Any] = []
    gyropipe_register_stages(defs.append)
    assert defs[0].name == "integrate_continuous"
    sim, stops = run()
    ctx: Any = SimpleNamespace(well=WellMetadata(latitude=LAT), stage_id="c")
    out = continuous_stage(
        {"samples": sim.samples, "stops": stops},
        ContinuousParams(spacing=10.0, odometer_window=0.07),
        ctx,
    )
    assert set(out) == {"stations", "series"}
    assert b"misclosure_deg" in (out["stations"].schema.metadata or {})
    assert out["stations"].num_rows > 20


def test_run_starting_near_vertical_is_tied_to_the_end_stop() -> None:
    """The start stop in the vertical section has no azimuth: integrate back from the end."""
    survey = {**SURVEY, "start_md": 5.0}
    sim = simulate(make_spec({"preset": "ideal", "overrides": {"gyro_axes": "x"}}, survey))
    _, stops, _ = compassed(sim.samples)
    result = integrate_continuous(
        sim.samples, stops, LAT, ContinuousOptions(spacing=5.0, odometer_window=0.07)
    )
    assert np.isnan(result.misclosure)
    flags = result.series.read_all().column("flags").to_numpy()
    assert np.all(flags & FLAG_NO_CLOSURE)
    err = usable_azimuth_error(result, sim)
    assert np.abs(err).max() < 0.01


def test_a_run_whose_end_stop_was_rejected_is_integrated_from_the_start_stop() -> None:
    """Compassing rejected the end stop (an ambiguous azimuth, say): the run is integrated
    forward from the start stop as without closure, and flagged so."""
    bias = 2.0  # deg/h: a drift the closure would have removed
    sim, stops = run(bias)
    last = int(np.max(stops.column("station").to_numpy()))
    kept = pc.not_equal(stops.column("station"), last)
    options = ContinuousOptions(spacing=5.0, odometer_window=0.07)
    result = integrate_continuous(sim.samples, stops.filter(kept), LAT, options)
    unclosed = integrate(bias, closure=False)
    assert np.isnan(result.misclosure) and not np.isnan(unclosed.misclosure)
    for name in ("md", "inc", "azi", "sigma_azi"):
        np.testing.assert_array_equal(
            result.stations.column(name).to_numpy(), unclosed.stations.column(name).to_numpy()
        )
    assert np.all(result.stations.column("flags").to_numpy() & FLAG_NO_CLOSURE)
    assert np.all(result.series.read_all().column("flags").to_numpy() & FLAG_NO_CLOSURE)
    # the drift stays, within the stated σ of the last station (seed 4: −0.28° against 0.80°)
    err = usable_azimuth_error(result, sim)
    sigma_end = result.stations.column("sigma_azi").to_numpy()[-1]
    assert 0.05 < abs(err[-1]) < 3 * sigma_end
