"""Continuous data on sliding windows against the simulator: stationary windows are the
tool's true stops, checks at rest pass on clean data and catch a biased gyro, motion bounds
and sensor ranges fail with window times, magnetic anomalies come out as MD intervals."""

from __future__ import annotations

from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pytest

from pipeline.earth.frames import body_to_ned, earth_rate_ned, to_body
from pipeline.earth.site import Site
from pipeline.qc.options import Limit, QcInputError, QcOptions, QcStop
from pipeline.qc.tables import MagneticAnomalies, QcResults
from pipeline.qc.windows import anomaly_intervals, stationary, window_checks
from pipeline.sim.simulate import Simulation, simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.streams import TableStream

SITE = {
    "latitude": 61.25,
    "longitude": 73.4,
    "date": "2026-11-21",
    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
}
WELL = {  # 0 … 800 m: vertical, build to 40° at 3°/30 m, hold
    "sections": [
        {"kind": "vertical", "length": 100},
        {"kind": "curve", "dls": 3.0, "inc": 40, "azi": 60},
        {"kind": "hold", "length": 300},
    ]
}
NOISY = {
    "sample_rate": 20,
    "gyro": {"noise_density": 0.003},
    "accelerometer": {"noise_density": 0.01},
    "magnetometer": {"noise_density": 2.0},
}


def run(survey: dict[str, Any], tool: dict[str, Any] | None = None, seed: int = 2):
    spec = SimulationSpec.model_validate(
        {
            "name": "windows",
            "seed": seed,
            "site": SITE,
            "well": WELL,
            "tool": {"preset": "ideal", "overrides": tool or NOISY},
            "survey": survey,
        }
    )
    return simulate(spec), spec.site


@pytest.fixture(scope="module")
def continuous() -> tuple[Simulation, Site]:
    return run({"mode": "continuous", "speed": 1.0})


def truly_still(sim: Simulation, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Windows in which the tool truly moves less than 5 cm and turns less than 0.5° (the
    detection thresholds allow a creep at the end of a stop's deceleration)."""
    truth = sim.truth
    time = truth.column("time").to_numpy()
    md = truth.column("md").to_numpy()
    frame = np.unwrap(np.radians(truth.column("frame_angle").to_numpy()))
    azi = truth.column("azi").to_numpy()  # the housing roll A + ψ is defined through vertical
    roll = np.unwrap(np.radians(azi + truth.column("housing_toolface").to_numpy()))
    out = []
    for a, b in zip(start, end, strict=True):
        at = (time >= a) & (time <= b)
        turn = max(np.ptp(frame[at]), np.ptp(roll[at]))
        out.append(np.ptp(md[at]) < 0.05 and np.degrees(turn) < 0.5)
    return np.array(out)


def test_stationary_windows_are_the_true_stops(continuous):
    sim, _ = continuous
    start, end, still = stationary(sim.samples)
    truth = truly_still(sim, start, end)
    assert still.sum() >= 40
    assert not np.any(still & ~truth)  # nothing moving is called stationary
    assert np.mean(still[truth]) >= 0.95
    point, _ = run({"mode": "point", "every": 100, "dwell": 12.0, "move_time": 2.0})
    start, end, still = stationary(point.samples, QcOptions(window=5.0, step=2.5))
    truth = truly_still(point, start, end)
    assert not np.any(still & ~truth)
    assert np.mean(still[truth]) >= 0.95 and still.sum() >= 100


@pytest.mark.parametrize("rows", [97, 4099])
def test_streamed_windows_give_the_whole_table_rows(continuous, rows):
    """Batches of 97 samples (shorter than a window) or 4099 cut the windows anywhere; the
    rows are those of the table in one batch, with the window's magnetometer checks too."""
    sim, site = continuous
    whole = window_checks(TableStream.from_table(sim.samples, sim.samples.num_rows), site)
    streamed = window_checks(TableStream.from_table(sim.samples, rows), site)
    assert whole.num_rows > 1000
    assert set(whole.column("check").to_pylist()) >= {"magnetic_field", "motion_rate"}
    assert streamed.equals(whole)


def test_clean_continuous_data_passes(continuous):
    sim, site = continuous
    qc = window_checks(sim.samples, site)
    QcResults.validate_table(qc)
    assert qc.column("station").null_count == qc.num_rows
    assert qc.column("window_start").null_count == 0
    failed = qc.filter(pc.equal(pc.fill_null(qc.column("passed"), True), False))
    assert failed.num_rows == 0, failed.to_pylist()[:3]
    checks = set(qc.column("check").to_pylist())
    assert {"earth_rate", "latitude", "motion_rate", "gyro_saturation", "magnetic_dip"} <= checks
    assert anomaly_intervals(qc).num_rows == 0
    dip = qc.filter(pc.equal(qc.column("check"), "magnetic_dip"))
    skipped = dip.filter(pc.is_null(dip.column("passed")))
    assert 0 < skipped.num_rows < 10  # the speed ramps: the tool accelerates
    assert "accelerates" in skipped.column("detail")[0].as_py()


def _replace(samples: pa.Table, columns: dict[str, np.ndarray]) -> pa.Table:
    for name, values in columns.items():
        i = samples.schema.get_field_index(name)
        samples = samples.set_column(i, samples.schema.field(name), pa.array(values))
    return samples


def test_magnetic_anomalies_come_out_as_md_intervals(continuous):
    """|B| 2 % high over MD 250–350 m; the field tilted 1° down (|B| kept) over 550–600 m."""
    sim, site = continuous
    samples = sim.samples
    md = samples.column("md").to_numpy()
    mag = np.stack([samples.column(f"mag_{a}").to_numpy() for a in "xyz"], axis=-1)
    acc = np.stack([samples.column(f"acc_{a}").to_numpy() for a in "xyz"], axis=-1)
    strong = (md >= 250) & (md <= 350)
    mag[strong] *= 1.02
    tilted = (md >= 550) & (md <= 600)
    b = mag[tilted] / np.linalg.norm(mag[tilted], axis=1, keepdims=True)
    down = acc[tilted] / np.linalg.norm(acc[tilted], axis=1, keepdims=True)
    across = down - np.sum(down * b, axis=1, keepdims=True) * b
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    angle = np.radians(1.0)
    mag[tilted] = np.linalg.norm(mag[tilted], axis=1, keepdims=True) * (
        np.cos(angle) * b + np.sin(angle) * across
    )
    samples = _replace(samples, {f"mag_{a}": mag[:, i] for i, a in enumerate("xyz")})
    qc = window_checks(samples, site)
    intervals = anomaly_intervals(qc)
    MagneticAnomalies.validate_table(intervals)
    rows = intervals.to_pylist()
    assert len(rows) == 2, rows
    first, second = rows
    reach = 10.0  # a 10 s window at 1 m/s
    assert 250 - reach <= first["md_from"] <= 250 + reach
    assert 350 - reach <= first["md_to"] <= 350 + reach
    assert first["field_error"] == pytest.approx(0.02 * 59731, rel=0.1)
    assert 550 - reach <= second["md_from"] and second["md_to"] <= 600 + reach
    assert second["dip_error"] == pytest.approx(1.0, abs=0.15)
    assert np.isnan(second["field_error"])


def test_motion_bounds_and_sensor_ranges_fail_with_window_times(continuous):
    sim, site = continuous
    tight = QcOptions(motion_rate=Limit(limit=10.0), motion_accel=Limit(limit=0.05))
    qc = window_checks(sim.samples, site, tight)
    for name in ("motion_rate", "motion_accel"):
        rows = qc.filter(pc.equal(qc.column("check"), name))
        failed = rows.filter(pc.invert(rows.column("passed")))
        assert 0 < failed.num_rows < rows.num_rows, name
        assert failed.column("window_start").null_count == 0
        assert all(failed.column("measured").to_numpy() > failed.column("tolerance").to_numpy())
    samples = sim.samples
    gyro = samples.column("gyro_z").to_numpy()
    clipped = np.clip(gyro, -30 * 3600, 30 * 3600)  # a ±30 deg/s gyro saturates
    assert np.any(clipped != gyro)
    qc = window_checks(
        _replace(samples, {"gyro_z": clipped}), site, QcOptions(gyro_saturation=Limit(limit=29.7))
    )
    rows = qc.filter(pc.equal(qc.column("check"), "gyro_saturation"))
    failed = rows.filter(pc.invert(rows.column("passed")))
    assert failed.num_rows > 0
    assert "exceeds the limit 29.7 deg/s" in failed.column("detail")[0].as_py()
    with pytest.raises(
        QcStop, match=r"window [0-9.]+–[0-9.]+ s \(md [0-9.]+ m\): check 'motion_rate'"
    ):
        window_checks(sim.samples, site, QcOptions(motion_rate=Limit(limit=10.0, policy="stop")))


def test_biased_gyro_fails_the_checks_at_rest_of_continuous_data():
    biased = {**NOISY, "gyro": {"noise_density": 0.003, "bias": [0, 2.0, 0]}}
    sim, site = run({"mode": "continuous", "speed": 1.0}, biased)
    qc = window_checks(sim.samples, site)
    rest = qc.filter(pc.equal(qc.column("check"), "horizontal_rate"))
    # forward model: the bias changes |ω_h| by |P(ω + b)| − |Pω| (P: across gravity), which
    # depends on the frame position — nearly nothing where b is across the Earth rate
    truth = sim.truth
    mid = (rest.column("window_start").to_numpy() + rest.column("window_end").to_numpy()) / 2
    t = truth.column("time").to_numpy()
    at = {n: np.radians(np.interp(mid, t, truth.column(n).to_numpy())) for n in ("inc", "azi")}
    tf = np.radians(np.interp(mid, t, np.unwrap(truth.column("toolface").to_numpy(), period=360)))
    c_bn = body_to_ned(at["azi"], at["inc"], tf)
    rate = to_body(c_bn, earth_rate_ned(np.radians(site.latitude))) * 180 / np.pi * 3600
    down = to_body(c_bn, np.array([0.0, 0.0, 1.0]))

    def across(v: np.ndarray) -> np.ndarray:
        return np.linalg.norm(v - np.sum(v * down, axis=1)[:, None] * down, axis=1)

    change = np.abs(across(rate + np.array([0.0, 2.0, 0.0])) - across(rate))
    tolerance = rest.column("tolerance").to_numpy()
    passed = np.asarray(rest.column("passed").to_pylist())
    assert np.sum(change > 2 * tolerance) >= 0.3 * rest.num_rows
    assert not passed[change > 2 * tolerance].any()
    assert passed[change < 0.5 * tolerance].all()
    failed = rest.filter(pc.invert(rest.column("passed")))
    suspects = set(failed.column("suspect").to_pylist())
    assert suspects <= {"gyro y", "undetermined"} and "gyro y" in suspects
    moving = qc.filter(pc.equal(qc.column("check"), "motion_rate"))
    assert all(moving.column("passed").to_pylist())


def test_too_short_or_bad_input_raises_typed_errors(continuous):
    sim, site = continuous
    with pytest.raises(QcInputError, match="shorter than one window"):
        window_checks(sim.samples.slice(0, 50), site)
    no_md = sim.samples.drop_columns(["md"])
    qc = window_checks(no_md, site)
    assert qc.column("md").null_count == qc.num_rows
    dip = qc.filter(pc.equal(qc.column("check"), "magnetic_dip"))
    still = qc.filter(pc.equal(qc.column("check"), "earth_rate")).num_rows
    assert dip.num_rows - dip.column("passed").null_count == still  # at rest only
