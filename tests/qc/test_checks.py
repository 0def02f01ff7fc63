"""Validity checks of point-survey readings against the simulator: the invariants and their
signs on noise-free data, the false-alarm rate of clean white-noise tools, detection of a
moving tool and of each sensor fault, policies, magnetometers, and bad metadata."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pytest
from qc_support import MAGNETIC, SITE, TRIM, point_run, random_well
from scipy.stats import binom
from scipy.stats import t as student_t

from pipeline.earth.frames import OMEGA_EARTH
from pipeline.earth.geomagnetic import ModelValidityError
from pipeline.earth.site import Site, resolve_site
from pipeline.errors import MissingSiteError
from pipeline.gyrocompass.readings import position_readings
from pipeline.qc.engine import drop_stations, station_checks
from pipeline.qc.options import QcInputError, QcOptions, QcStop, Tolerance
from pipeline.qc.tables import QcResults, QcSummary
from pipeline.well import WellMetadata

OMEGA_DEG_H = np.degrees(OMEGA_EARTH) * 3600
WHITE = {  # white noise only: per-position means have σ = std/√n exactly
    "sample_rate": 50,
    "gyro": {"noise_density": 0.003},
    "accelerometer": {"noise_density": 0.01},
    "magnetometer": {"noise_density": 2.0},
}
GYRO_ACC = ("earth_rate", "gravity", "latitude", "horizontal_rate", "rate_along_gravity")
SIGMA_ONLY = QcOptions(**{name: Tolerance(sigma=3) for name in GYRO_ACC})
"""3σ and no floors: the false-alarm rate of white noise is 0.27 % per reading."""


def failure_rates(qc: pa.Table) -> dict[str, tuple[int, int]]:
    """Per check: (failed rows, evaluated rows)."""
    out = {}
    for name in set(qc.column("check").to_pylist()):
        rows = qc.filter(pc.equal(qc.column("check"), name))
        passed = rows.column("passed").drop_null().to_numpy(zero_copy_only=False)
        out[name] = (int((~passed).sum()), len(passed))
    return out


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    """≥ 500 stations of five positions, three-axis white-noise tool with magnetometers."""
    well = random_well(tmp_path_factory.mktemp("clean") / "well.csv", 520, seed=11)
    return point_run(well, WHITE)


@pytest.mark.parametrize("latitude", [61.25, -35.0, 0.0])
def test_invariants_and_the_sign_of_omega_dot_g_on_noise_free_data(tmp_path: Path, latitude):
    """ω·g = −Ω sin φ |g| (g_b points down): negative north of the equator, positive south;
    every measured invariant equals its reference to rounding."""
    site = {**SITE, "latitude": latitude}
    sim, readings, site_model = point_run(
        random_well(tmp_path / "w.csv", 12, seed=3), {}, site=site
    )
    qc, summary = station_checks(readings, site_model, samples=sim.samples)
    QcResults.validate_table(qc)
    QcSummary.validate_table(summary)
    assert set(summary.column("status").to_pylist()) == {"ok"}
    phi = np.radians(latitude)
    expected = {
        "earth_rate": OMEGA_DEG_H,
        "gravity": site_model.gravity,
        "latitude": latitude,
        "horizontal_rate": OMEGA_DEG_H * np.cos(phi),
        "rate_along_gravity": -OMEGA_DEG_H * np.sin(phi),
        "magnetic_field": MAGNETIC["total_field"],
        "magnetic_dip": MAGNETIC["dip"],
    }
    for name, value in expected.items():
        rows = qc.filter(pc.equal(qc.column("check"), name))
        assert rows.num_rows == readings.num_rows
        np.testing.assert_allclose(rows.column("measured").to_numpy(), value, atol=1e-9)
        np.testing.assert_allclose(rows.column("reference").to_numpy(), value, atol=1e-12)
    if latitude:
        along = qc.filter(pc.equal(qc.column("check"), "rate_along_gravity"))
        assert np.all(np.sign(along.column("measured").to_numpy()) == -np.sign(latitude))


def test_false_alarm_rate_of_a_clean_white_noise_tool(clean):
    """3σ without floors: each gyro/accelerometer check fails on 0.27 % of readings for a
    known σ, up to 0.37 % (Student t, 74 dof) as σ comes from the std of 75 samples — within
    the binomial 99.9 % band of that; with the default floors nothing fails; the magnetic
    checks (absolute tolerances) and the rest checks never fail."""
    sim, readings, site = clean
    assert readings.num_rows >= 2500
    n = int(readings.column("n")[0].as_py())
    rate = 2 * student_t.sf(3, n - 1)
    qc, _ = station_checks(readings, site, SIGMA_ONLY, samples=sim.samples)
    rates = failure_rates(qc)
    pooled = [0, 0]
    for name in GYRO_ACC:
        failed, total = rates[name]
        print(f"{name}: {failed}/{total} = {failed / total:.4f}")
        assert failed <= binom.interval(0.999, total, rate)[1], (name, failed, total)
        pooled[0] += failed
        pooled[1] += total
    assert 0.5 * 0.0027 < pooled[0] / pooled[1] < 1.5 * rate, pooled
    for name in ("magnetic_field", "magnetic_dip", "rest_gyro", "rest_acc"):
        assert rates[name] == (0, readings.num_rows), name
    default, summary = station_checks(readings, site, samples=sim.samples)
    assert sum(f for f, _ in failure_rates(default).values()) == 0
    assert set(summary.column("status").to_pylist()) == {"ok"}


def test_single_axis_tool_gets_the_fitted_earth_rate_check_instead(tmp_path: Path):
    """A single-axis gyro cannot form |ω|: those checks are rows saying so (passed null);
    the fitted horizontal Earth rate k = √((u'/cos I)² + v²) is checked per station and
    fails at the 3σ rate on clean data."""
    tool = {
        "gyro_axes": "x",
        "sample_rate": 50,
        "gyro": {"noise_density": 0.003, "bias": [4.0, 0, 0], "bias_trend": [1.0, 0, 0]},
        "accelerometer": {"noise_density": 0.01},
    }
    well = random_well(tmp_path / "w.csv", 600, seed=5, inc=(5, 80))
    _, readings, site = point_run(well, tool)
    options = QcOptions(earth_rate_fit=Tolerance(sigma=3))
    qc, _ = station_checks(readings, site, options)
    fit = qc.filter(pc.equal(qc.column("check"), "earth_rate_fit"))
    assert fit.num_rows == readings.column("station").to_numpy().max() + 1
    assert fit.column("position").null_count == fit.num_rows
    evaluated = fit.filter(pc.is_valid(fit.column("passed")))
    assert evaluated.num_rows >= 590  # the vertical first station is near vertical: frame
    measured = evaluated.column("measured").to_numpy()
    k = OMEGA_DEG_H * np.cos(np.radians(61.25))
    z = (measured - k) / (evaluated.column("tolerance").to_numpy() / 3)
    assert abs(np.median(z)) < 0.15 and 0.85 < np.std(z) < 1.15  # the σ is right
    failed = int((~evaluated.column("passed").to_numpy(zero_copy_only=False)).sum())
    print(f"earth_rate_fit: {failed}/{evaluated.num_rows}")
    assert failed <= binom.interval(0.999, evaluated.num_rows, 0.0037)[1]
    skipped = qc.filter(pc.equal(qc.column("check"), "earth_rate"))
    assert skipped.column("passed").null_count == skipped.num_rows
    assert "needs a three-axis gyro" in skipped.column("detail")[0].as_py()
    assert "gravity" in set(qc.column("check").to_pylist())


@pytest.mark.parametrize(("axes", "positions"), [("x", (0, 90, 180, 270, 0)), ("xy", (0, 180, 0))])
def test_single_axis_and_xy_scale_errors_fail_the_fitted_earth_rate(
    tmp_path: Path, axes, positions
):
    """A 10 % gyro scale error s: the fit gives u' = (1 + s) k cos A cos I + s Ω sin φ sin I
    (the scaled vertical-rate leak is not fully removed) and v' = −(1 + s) k sin A, so k
    comes out mostly too large: the fit check fails and, the axis being unknowable from a
    fit, says 'undetermined'."""
    tool = {
        "gyro_axes": axes,
        "sample_rate": 50,
        "gyro": {"noise_density": 0.003, "bias": [3.0, -2.0, 0], "scale_factor": [1e5, 1e5, 0]},
        "accelerometer": {"noise_density": 0.01},
    }
    well = random_well(tmp_path / "w.csv", 40, seed=6, inc=(5, 70))
    sim, readings, site = point_run(well, tool, positions=positions)
    qc, summary = station_checks(readings, site, QcOptions(earth_rate_fit=Tolerance(sigma=3)))
    fit = qc.filter(pc.equal(qc.column("check"), "earth_rate_fit"))
    fit = fit.filter(pc.greater(fit.column("md"), 1.0))  # the vertical first station aside
    inc, azi = (np.radians(sim.stations.column(c).to_numpy()[1:]) for c in ("inc", "azi"))
    phi, k = np.radians(61.25), OMEGA_DEG_H * np.cos(np.radians(61.25))
    u = 1.1 * k * np.cos(azi) * np.cos(inc) + 0.1 * OMEGA_DEG_H * np.sin(phi) * np.sin(inc)
    expected = np.hypot(u / np.cos(inc), 1.1 * k * np.sin(azi))
    z = (fit.column("measured").to_numpy() - expected) / (fit.column("tolerance").to_numpy() / 3)
    assert np.abs(z).max() < 4
    failed = fit.filter(pc.equal(pc.fill_null(fit.column("passed"), True), False))
    assert failed.num_rows >= 0.7 * fit.num_rows
    assert set(failed.column("suspect").to_pylist()) == {"undetermined"}
    flagged = summary.filter(pc.equal(summary.column("status"), "flag"))
    assert set(flagged.column("suspect").to_pylist()) == {"undetermined"}


def _stations_failing(qc: pa.Table, check: str) -> set[int]:
    rows = qc.filter(pc.equal(qc.column("check"), check))
    failed = pc.equal(pc.fill_null(rows.column("passed"), True), False)
    return set(rows.filter(failed).column("station").to_pylist())


@pytest.mark.parametrize(
    ("fault", "checks"),
    [
        ({"gyro": {"bias": [0, 2.0, 0]}}, {"earth_rate", "horizontal_rate", "latitude"}),
        ({"accelerometer": {"scale_factor": [0, 0, 20000]}}, {"gravity"}),
        (  # gyro triad rotated 0.2 rad about x: only the coupled checks see it
            {"gyro": {"misalignment": [[0, 0, 0], [0, 0, -200], [0, 200, 0]]}},
            {"latitude", "rate_along_gravity", "horizontal_rate"},
        ),
    ],
)
def test_each_injected_sensor_fault_is_detected(tmp_path: Path, fault, checks):
    tool = {**WHITE, **{k: {**WHITE[k], **v} for k, v in fault.items()}}
    sim, readings, site = point_run(random_well(tmp_path / "w.csv", 60, seed=7), tool)
    qc, summary = station_checks(readings, site, samples=sim.samples)
    stations = summary.num_rows
    flagged = summary.filter(pc.equal(summary.column("status"), "flag")).num_rows
    assert flagged >= 0.8 * stations, (flagged, stations)
    seen = {c for c in checks if _stations_failing(qc, c)}
    assert seen == checks
    if "misalignment" in fault.get("gyro", {}):  # magnitudes are blind to a rotation
        assert len(_stations_failing(qc, "earth_rate")) <= 2


def test_tool_moving_during_a_station_is_detected_and_dropped(tmp_path: Path):
    sim, _, site = point_run(random_well(tmp_path / "w.csv", 8, seed=2), WHITE)
    samples = sim.samples
    station = samples.column("station").to_numpy(zero_copy_only=False)
    position = samples.column("position").to_numpy(zero_copy_only=False)
    at = np.flatnonzero((station == 4) & (position == 2))
    time = samples.column("time").to_numpy()
    wobble = np.sin(2 * np.pi * 0.7 * (time[at] - time[at[0]]))
    corrupted = {}
    for name, amplitude in (("gyro_z", 5000.0), ("acc_x", 0.2), ("acc_y", -0.2)):
        values = samples.column(name).to_numpy().copy()
        values[at] += amplitude * wobble  # the tool rocks: 1.4 °/s, 0.2 m/s²
        corrupted[name] = values
    for name, values in corrupted.items():
        i = samples.schema.get_field_index(name)
        samples = samples.set_column(i, samples.schema.field(name), pa.array(values))
    readings = position_readings(samples, TRIM)
    qc, summary = station_checks(readings, site)
    assert _stations_failing(qc, "rest_gyro") == {4}
    assert _stations_failing(qc, "rest_acc") == {4}
    stations = summary.column("station").to_pylist()
    status = dict(zip(stations, summary.column("status").to_pylist(), strict=True))
    assert status[4] == "drop" and {s for s, v in status.items() if v != "ok"} == {4}
    kept = drop_stations(readings, summary)
    assert 4 not in set(kept.column("station").to_pylist())
    assert kept.num_rows == readings.num_rows - 5


def test_stop_policy_raises_naming_station_and_check(tmp_path: Path):
    tool = {**WHITE, "accelerometer": {"noise_density": 0.01, "bias": [0, 0, 0.05]}}
    _, readings, site = point_run(random_well(tmp_path / "w.csv", 3, seed=2), tool)
    options = QcOptions(gravity=Tolerance(sigma=3, absolute=0.012, policy="stop"))
    with pytest.raises(QcStop, match=r"station 0 \(md 0 m\): check 'gravity' failed") as info:
        station_checks(readings, site, options)
    assert info.value.check == "gravity"
    assert info.value.summary is not None
    assert info.value.summary.column("status")[0].as_py() == "stop"


def test_magnetometers_are_averaged_from_the_samples_of_each_reading(tmp_path: Path):
    sim, readings, site = point_run(random_well(tmp_path / "w.csv", 5, seed=4), WHITE)
    samples = sim.samples
    for name in ("mag_x", "mag_y", "mag_z"):  # the field 1 % (597 nT) stronger: |B| fails
        i = samples.schema.get_field_index(name)
        mag = samples.column(name).to_numpy() * 1.01
        samples = samples.set_column(i, samples.schema.field(name), pa.array(mag))
    qc, _ = station_checks(readings, site, samples=samples)
    field = qc.filter(pc.equal(qc.column("check"), "magnetic_field"))
    assert not any(field.column("passed").to_pylist())
    # per sample σ = 2 nT/√Hz · √50 Hz = 14 nT, 1.6 nT for the mean of 75: within 5σ
    np.testing.assert_allclose(field.column("measured").to_numpy(), 1.01 * 59731.0, atol=8.0)
    dip = qc.filter(pc.equal(qc.column("check"), "magnetic_dip"))
    assert all(dip.column("passed").to_pylist())
    assert qc.filter(pc.equal(qc.column("check"), "magnetic_dip")).num_rows == readings.num_rows
    no_mag, _ = station_checks(readings, site)
    assert "magnetic_field" not in set(no_mag.column("check").to_pylist())
    with pytest.raises(QcInputError, match="n/duration"):
        station_checks(readings.drop_columns(["n", "duration"]), site, samples=samples)
    with pytest.raises(QcInputError, match="the samples hold"):
        station_checks(readings, site, samples=samples.slice(0, 3000))


def test_readings_without_std_are_checked_against_the_absolute_parts_only(tmp_path: Path):
    _, readings, site = point_run(random_well(tmp_path / "w.csv", 3, seed=4), WHITE)
    bare = readings.drop_columns([c for c in readings.column_names if c.endswith("_std")])
    qc, _ = station_checks(bare, site)
    earth = qc.filter(pc.equal(qc.column("check"), "earth_rate"))
    np.testing.assert_allclose(earth.column("tolerance").to_numpy(), 0.5)
    assert all("σ unknown" in d for d in earth.column("detail").to_pylist())
    rest = qc.filter(pc.equal(qc.column("check"), "rest_gyro"))
    assert rest.column("passed").null_count == rest.num_rows
    sigma_only, _ = station_checks(bare, site, SIGMA_ONLY)
    gravity = sigma_only.filter(pc.equal(sigma_only.column("check"), "gravity"))
    assert gravity.column("passed").null_count == gravity.num_rows


def test_bad_metadata_raises_typed_errors(tmp_path: Path):
    def qc_site(well: WellMetadata) -> Site:
        return resolve_site(well, stage="validity_checks", param=None, field=True)

    with pytest.raises(MissingSiteError, match="latitude"):
        qc_site(WellMetadata(longitude=73.4, survey_date=dt.date(2026, 11, 21)))
    with pytest.raises(MissingSiteError, match="survey_date"):
        qc_site(WellMetadata(latitude=61.25, longitude=73.4))
    with pytest.raises(MissingSiteError, match="longitude"):
        qc_site(WellMetadata(latitude=61.25, survey_date=dt.date(2026, 11, 21)))
    site = qc_site(WellMetadata(latitude=61.25, longitude=73.4, survey_date=dt.date(2026, 11, 21)))
    assert site.latitude == 61.25 and site.magnetic is None

    sim, readings, _ = point_run(random_well(tmp_path / "w.csv", 2, seed=4), WHITE)
    old = Site(latitude=61.25, longitude=73.4, date=dt.date(2019, 6, 1))  # before WMM2025
    with pytest.raises(ModelValidityError, match="WMM2025 is valid from 2025-01-01"):
        station_checks(readings, old, samples=sim.samples)
    station_checks(readings, old)  # without magnetometers the date does not matter
    qc, _ = station_checks(  # IGRF-14 at the site agrees with the simulated (WMM) field
        readings,
        Site(latitude=61.25, longitude=73.4, date=dt.date(2026, 11, 21)),
        QcOptions(magnetic_model="igrf14"),
        samples=sim.samples,
    )
    dip = qc.filter(pc.equal(qc.column("check"), "magnetic_dip"))
    np.testing.assert_allclose(dip.column("reference").to_numpy(), 78.29, atol=0.1)
