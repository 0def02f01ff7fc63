"""Drift correction of simulated free-gyro surveys: corrected azimuths within their predicted
σ (tie-in, given and calibrated rates), in/out-run QC flags, and the free-gyro pipeline."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from pipeline.drift.calibration import CalibrationOptions, calibrate
from pipeline.drift.correction import (
    CorrectionOptions,
    DriftRate,
    chi2_median_mean,
    correct_survey,
)
from pipeline.drift.tables import CorrectedFreeGyroReadings, DriftStations, InOutQc
from pipeline.errors import InputFileWarning
from pipeline.graph import build_plan
from pipeline.io import drift_tables
from pipeline.io.csv import write_csv
from pipeline.plugins import load_registry
from pipeline.registry import PluginInfo, ReaderDef, Registry, StageDef
from pipeline.runner import run_plan
from pipeline.sim.calibration import CalibrationPlan, simulate_calibration
from pipeline.sim.freegyro import simulate_free_gyro
from pipeline.sim.spec import Drift, SimulationSpec
from pipeline.spec import load_spec
from pipeline.stages import drift as drift_plugin
from pipeline.well import WellMetadata
from tests_support import ROOT, gyropipe_cli, stage_context

NOISE = 0.2  # deg, σ of an azimuth reading
RATE = 3.0  # deg/h
ROWS = [15, 40, 60]  # an in-run, a deep in-run and an out-run reading (inclined)


def spec(seed: int = 0, **survey: object) -> SimulationSpec:
    return SimulationSpec.model_validate(
        {
            "name": "free",
            "seed": seed,
            "site": {"latitude": 61.25, "longitude": 73.4, "date": "2026-11-21"},
            "well": {
                "sections": [
                    {"kind": "vertical", "length": 200},
                    {"kind": "build", "dls": 3.0, "inc": 40, "azi": 37},
                    {"kind": "hold", "to_md": 1200},
                ]
            },
            "tool": {"preset": "mems-vrg"},
            "survey": {
                "mode": "free_gyro",
                "every": 30,
                "reading_noise": NOISE,
                "drift": {"offset": 0.7, "rate": RATE},
            }
            | survey,
        }
    )


def azimuth_error(table: pa.Table) -> np.ndarray:
    err = table.column("azi").to_numpy() - table.column("true_azi").to_numpy()
    return (err + 180) % 360 - 180


def normalised(options: CorrectionOptions, rate_sigma: float | None, runs: int) -> np.ndarray:
    """(runs, len(ROWS)) errors of corrected azimuths over their predicted σ."""
    z = []
    for seed in range(runs):
        readings = simulate_free_gyro(spec(seed))
        rate = None
        if rate_sigma is not None:  # a calibrated rate: true rate + its own error
            error = np.random.default_rng([seed, 99]).normal(0.0, rate_sigma)
            rate = DriftRate(rate=RATE + error, sigma=rate_sigma, source="given")
        ref = readings.column("true_azi")[0].as_py()
        out = correct_survey(readings, options.model_copy(update={"reference_azimuth": ref}), rate)
        sigma = out.readings.column("sigma_azi").to_numpy()
        z.append(azimuth_error(out.readings)[ROWS] / sigma[ROWS])
    return np.array(z)


def test_tie_in_correction_restores_the_survey_within_predicted_error():
    readings = simulate_free_gyro(spec())
    assert readings.column("run")[ROWS[-1]].as_py() == "out"
    assert np.all(readings.column("true_inc").to_numpy()[ROWS] > 10)
    z = normalised(CorrectionOptions(reading_sigma=NOISE), None, 300)
    assert np.all((z.std(axis=0) > 0.8) & (z.std(axis=0) < 1.2)), z.std(axis=0)
    assert np.all(np.abs(z.mean(axis=0)) < 0.15)


@pytest.mark.parametrize("reading_sigma", [NOISE, None])
def test_calibrated_rate_correction_carries_the_rate_sigma(reading_sigma: float | None):
    """σ_r given or estimated: the estimate blind to the rate's error, which all the in/out
    differences share (seen, it was taken for reading noise: σ̂_r² 2.3 × σ_r², azimuth
    error/σ scatter 1.26 at row 15 and 0.79 at row 60)."""
    z = normalised(CorrectionOptions(reading_sigma=reading_sigma), 0.5, 300)
    assert np.all((z.std(axis=0) > 0.88) & (z.std(axis=0) < 1.12)), z.std(axis=0)
    assert np.all(np.abs(z.mean(axis=0)) < 0.15)


def test_the_tie_in_rate_s_sigma_is_its_scatter():
    """Over 300 simulated surveys drifting RATE, the tie-in misclosure's rate scatters by the
    σ it states, √2·σ_r over the time between its two readings (σ_r given); the corrected
    readings carry both, in deg/h."""
    z = []
    for seed in range(300):
        out = correct_survey(simulate_free_gyro(spec(seed)), CorrectionOptions(reading_sigma=NOISE))
        z.append((out.rate.rate - RATE) / out.rate.sigma)
        for name, value in (("drift_rate", out.rate.rate), ("sigma_drift_rate", out.rate.sigma)):
            assert out.readings.column(name).to_pylist() == [value] * out.readings.num_rows
            assert out.readings.schema.field(name).metadata[b"unit"] == b"deg/h"
    assert 0.85 < np.std(z) < 1.15 and abs(np.mean(z)) < 0.15, (np.std(z), np.mean(z))


def test_an_estimated_reading_sigma_gives_the_tie_in_rate_s_sigma():
    """σ_r estimated from the in/out pairs: the rate's σ is √2·σ_r over the tie readings'
    time apart (the first in-run and the last out-run reading at station 0)."""
    readings = simulate_free_gyro(spec(3))
    out = correct_survey(readings, CorrectionOptions())
    rows = readings.select(["run", "station", "time"]).to_pylist()
    first = next(r["time"] for r in rows if r["station"] == 0 and r["run"] == "in")
    last = [r["time"] for r in rows if r["station"] == 0 and r["run"] == "out"][-1]
    expected = np.sqrt(2.0) * out.reading_sigma / ((last - first) / 3600.0)
    assert out.rate.sigma == pytest.approx(expected, rel=1e-12) and out.rate.sigma > 0


def test_a_given_rate_keeps_its_sigma():
    out = correct_survey(
        simulate_free_gyro(spec()),
        CorrectionOptions(),
        DriftRate(rate=2.5, sigma=0.125, source="given"),
    )
    assert out.readings.column("drift_rate")[0].as_py() == 2.5
    assert out.readings.column("sigma_drift_rate")[0].as_py() == 0.125


def test_reading_sigma_is_estimated_from_the_in_out_pairs():
    estimates = [
        correct_survey(simulate_free_gyro(spec(seed)), CorrectionOptions()).reading_sigma
        for seed in range(60)
    ]
    assert np.mean(estimates) == pytest.approx(NOISE, rel=0.1)


def test_chi2_median_mean_is_the_expected_sample_median():
    """One value's (or two's, their mean) is χ²₁'s mean, 1; many values' tends to χ²₁'s
    median; 3, 4 and 39 values' against the median of as many draws, 200 000 times."""
    assert chi2_median_mean(1) == pytest.approx(1.0, rel=1e-9)
    assert chi2_median_mean(2) == pytest.approx(1.0, rel=1e-9)
    assert chi2_median_mean(20001) == pytest.approx(0.454936, rel=3e-4)
    rng = np.random.default_rng(30)
    for n in (3, 4, 39):
        drawn = np.median(rng.chisquare(1.0, (200_000, n)), axis=1)
        standard_error = drawn.std() / np.sqrt(len(drawn))  # 0.1–0.2 % of the mean
        assert abs(chi2_median_mean(n) - drawn.mean()) < 4 * standard_error, n


def test_an_estimated_reading_sigma_is_unbiased_and_blind_to_the_rate_s_error():
    """σ_r estimated (the free-gyro default) over 300 simulated surveys of 39 pairs besides
    the tie-in: σ̂_r² averages σ_r² (the median's small-sample bias, +5 % here, removed) and
    is uncorrelated with the tie-in rate's error (the differences' rate line removed; the
    estimate from the corrected differences saw that error: correlation +0.67, σ̂_r² +10 %,
    rate error/σ scatter 0.85, 99 % within ±1.96 σ, all outside these bands). So the
    rate's and three azimuths' errors over their stated σ scatter by 1 and ±1.96 σ holds
    95 %, less what the estimate's own scatter costs (~15 degrees of freedom: ~+4 %, ~94 %).
    Bands: about 3 standard errors of 300 surveys."""
    ratio, err, z_rate, z_azi = [], [], [], []
    for seed in range(300):
        readings = simulate_free_gyro(spec(seed))
        ref = readings.column("true_azi")[0].as_py()
        out = correct_survey(readings, CorrectionOptions(reference_azimuth=ref))
        ratio.append((out.reading_sigma / NOISE) ** 2)
        err.append(abs(out.rate.rate - RATE))
        z_rate.append((out.rate.rate - RATE) / out.rate.sigma)
        z_azi.extend(azimuth_error(out.readings)[ROWS] / out.readings["sigma_azi"].to_numpy()[ROWS])
    assert 0.94 < np.mean(ratio) < 1.06, np.mean(ratio)
    assert abs(np.corrcoef(err, ratio)[0, 1]) < 0.18, np.corrcoef(err, ratio)[0, 1]
    for z in (np.array(z_rate), np.array(z_azi)):
        assert 0.92 < np.std(z) < 1.12 and abs(np.mean(z)) < 0.15, (np.std(z), np.mean(z))
        assert 0.91 < np.mean(np.abs(z) < 1.96) < 0.98, np.mean(np.abs(z) < 1.96)


def test_a_bad_station_moves_neither_the_rate_line_nor_the_estimate():
    """A shallow station's out-run reading 2.4° (12 σ) off: σ̂_r within 3 % of the clean
    survey's on average (were it kept in the rate line removed from the differences, it
    would drag every other pair's residual with it: +9 %)."""
    change = []
    for seed in range(40):
        readings = simulate_free_gyro(spec(seed))
        clean = correct_survey(readings, CorrectionOptions()).reading_sigma
        run = np.array(readings.column("run").to_pylist())
        azi = readings.column("azi").to_numpy().copy()
        bad = int(np.flatnonzero((run == "out") & (readings.column("station").to_numpy() == 1))[0])
        azi[bad] = (azi[bad] + 2.4) % 360
        faulty = readings.set_column(
            readings.column_names.index("azi"), readings.schema.field("azi"), pa.array(azi)
        )
        change.append(correct_survey(faulty, CorrectionOptions()).reading_sigma / clean)
    assert abs(np.mean(change) - 1.0) < 0.03, np.mean(change)


def test_uncorrected_drift_is_removed_and_outputs_keep_their_contracts():
    readings = simulate_free_gyro(spec(4))
    before = np.abs(azimuth_error(readings)).max()
    out = correct_survey(readings, CorrectionOptions(reference_azimuth=0.0))
    CorrectedFreeGyroReadings.validate_table(out.readings)
    DriftStations.validate_table(out.stations)
    InOutQc.validate_table(out.qc)
    assert before > 3.0  # drift of ~3 °/h over the run
    assert np.abs(azimuth_error(out.readings)).max() < 5 * NOISE
    assert out.rate.rate == pytest.approx(RATE, abs=0.3)
    raw = out.readings.column("azi_raw").to_numpy() - out.readings.column("correction").to_numpy()
    residue = (raw - out.readings.column("azi").to_numpy() + 180) % 360 - 180
    assert np.abs(residue).max() < 1e-9
    stations = out.stations
    assert stations.num_rows == len(set(readings.column("station").to_pylist()))
    assert stations.schema.field("azi").metadata[b"north_reference"] == b"true"
    assert stations.column("readings").to_pylist()[-1] == 1  # the deepest is read once
    assert out.qc.column("passed").to_pylist() == [True] * out.qc.num_rows


def test_in_out_qc_flags_injected_station_errors():
    readings = simulate_free_gyro(spec(5))
    out = correct_survey(readings, CorrectionOptions())
    assert all(out.qc.column("passed").to_pylist())  # clean survey passes
    station = readings.column("station").to_numpy()
    run = np.array(readings.column("run").to_pylist())
    azi, inc = readings.column("azi").to_numpy().copy(), readings.column("inc").to_numpy().copy()
    bad_azi = int(np.flatnonzero((run == "out") & (station == 20))[0])  # inclined station
    bad_inc = int(np.flatnonzero((run == "in") & (station == 30))[0])
    azi[bad_azi] = (azi[bad_azi] + 2.5) % 360  # beyond the 1° tolerance
    inc[bad_inc] += 0.5  # beyond 0.23°
    vertical = int(np.flatnonzero((run == "out") & (station == 3))[0])
    azi[vertical] = (azi[vertical] + 3.0) % 360  # within 5° below 10° inclination
    faulty = readings.set_column(
        readings.column_names.index("azi"), readings.schema.field("azi"), pa.array(azi)
    ).set_column(readings.column_names.index("inc"), readings.schema.field("inc"), pa.array(inc))
    qc = correct_survey(faulty, CorrectionOptions()).qc.to_pydict()
    failed = {s for s, ok in zip(qc["station"], qc["passed"], strict=True) if not ok}
    assert failed == {20, 30}
    low = qc["station"].index(3)
    assert qc["azi_tolerance"][low] == 5.0 and abs(qc["azi_diff"][low]) > 2.5


def test_tie_in_needs_the_out_run():
    readings = simulate_free_gyro(spec(out_run=False))
    with pytest.raises(ValueError, match="tie-in needs"):
        correct_survey(readings, CorrectionOptions(reading_sigma=NOISE))
    out = correct_survey(
        readings,
        CorrectionOptions(reading_sigma=NOISE),
        DriftRate(rate=RATE, sigma=0.0, source="given"),
    )
    assert out.qc.num_rows == 0 and out.stations.num_rows == readings.num_rows


def _context(serial: str | None) -> SimpleNamespace:
    return stage_context(WellMetadata(tool_serial=serial), stage_id="drift")


def test_correct_stage_uses_the_calibration_of_the_tool_serial():
    calibration, _ = calibrate(
        pa.concat_tables(
            [
                simulate_calibration(
                    CalibrationPlan(instrument="IG50-1", reading_noise=0.5, drift=Drift(rate=RATE))
                ),
                simulate_calibration(CalibrationPlan(instrument="IG50-2", seed=2)),
            ]
        ),
        CalibrationOptions(),
    )
    readings = simulate_free_gyro(spec(7))
    inputs = {"readings": readings, "calibration": calibration}
    out = drift_plugin.correct_stage(inputs, CorrectionOptions(), _context("IG50-1"))
    fit = calibration.filter(calibration.column("selected")).to_pylist()[0]
    expected = fit["drift_deg_h"] * (readings.column("time").to_numpy() - 15.0) / 3600
    np.testing.assert_allclose(out["readings"].column("correction").to_numpy(), expected)
    with pytest.raises(ValueError, match="holds no estimate of instrument 'X'"):
        drift_plugin.correct_stage(inputs, CorrectionOptions(), _context("X"))
    with pytest.raises(ValueError, match="tool serial is stated nowhere"):
        drift_plugin.correct_stage(inputs, CorrectionOptions(), _context(None))
    given = drift_plugin.correct_stage(
        {"readings": readings}, CorrectionOptions(drift_rate=2.0), _context(None)
    )
    assert given["readings"].column("correction")[-1].as_py() == pytest.approx(
        2.0 * (readings.column("time")[-1].as_py() - 15.0) / 3600
    )


def test_non_linear_calibration_is_refused_unless_allowed():
    calibration, _ = calibrate(
        simulate_calibration(
            CalibrationPlan(drift=Drift(rate=RATE, curvature=120.0), reading_noise=2.0)
        ),
        CalibrationOptions(),
    )
    inputs = {"readings": simulate_free_gyro(spec()), "calibration": calibration}
    with pytest.raises(ValueError, match="non-linear"):
        drift_plugin.correct_stage(inputs, CorrectionOptions(), _context(None))
    out = drift_plugin.correct_stage(
        inputs, CorrectionOptions(allow_nonlinear=True, estimate="mean"), _context(None)
    )
    assert out["qc"].num_rows > 0


def drift_registry() -> Registry:
    """The real registry, with the drift plugin added unless it is already built in."""
    registry = load_registry()
    if "correct_drift" not in registry.stages:
        plugin = PluginInfo("builtin.drift", "test", builtin=True)
        registry.plugins[plugin.name] = plugin
        drift_plugin.gyropipe_register_stages(lambda s: registry.add(s, plugin, StageDef))
    if "drift_tables" not in registry.readers:
        plugin = PluginInfo("builtin.drift_tables", "test", builtin=True)
        registry.plugins[plugin.name] = plugin
        drift_tables.gyropipe_register_readers(lambda r: registry.add(r, plugin, ReaderDef))
    assert not registry.problems, registry.problems
    return registry


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_free_gyro_pipeline(tmp_path: Path, fmt: str):
    readings = simulate_free_gyro(spec(8))
    path = tmp_path / f"readings.{fmt}"
    if fmt == "parquet":
        pq.write_table(readings, path)
    else:
        write_csv(readings, path, WellMetadata(well="free"))
    registry = drift_registry()
    plan = build_plan(load_spec(ROOT / "pipelines" / "free-gyro.yaml"), registry)
    run_plan(plan, registry, inputs={"readings": path}, out_dir=tmp_path / "out")
    qc = pq.read_table(tmp_path / "out" / "drift.qc.parquet")
    assert all(qc.column("passed").to_pylist())
    trajectory = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet")
    stations = pq.read_table(tmp_path / "out" / "drift.stations.parquet")
    assert trajectory.num_rows == stations.num_rows
    inclined = trajectory.column("inc").to_numpy() > 10
    # no reference azimuth: corrected azimuths keep the orientation offset at the tie-in
    offset = readings.column("azi")[0].as_py() - readings.column("true_azi")[0].as_py()
    truth = readings.filter(pa.compute.equal(readings.column("run"), "in"))
    err = trajectory.column("azi").to_numpy() - truth.column("true_azi").to_numpy() - offset
    assert np.all(np.abs((err[inclined] + 180) % 360 - 180) < 4 * NOISE)


def test_a_readings_csv_naming_its_north_is_the_runs_well_north(tmp_path: Path):
    # '# north_reference=grid' above the header: the azimuths were grid, yet free-gyro.yaml's
    # well (true) stood in run.json and the trajectory's well beside them
    readings = simulate_free_gyro(spec(8))
    path = tmp_path / "readings.csv"
    write_csv(readings, path, WellMetadata(well="free"))
    text = path.read_text()
    assert "# north_reference=true\n" in text and "well.north_reference" not in text
    path.write_text(text.replace("# north_reference=true\n", "# north_reference=grid\n"))
    table, well = drift_tables.read_drift_table(path, "free_gyro", None)
    assert table.schema.field("azi").metadata[b"north_reference"] == b"grid"
    assert well.north_reference == "grid"
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run",
        ROOT / "pipelines" / "free-gyro.yaml",
        "--input",
        path,
        "--out",
        out,
        "--set",
        "report.formats=[html]",
    )
    assert result.returncode == 0, result.stderr
    assert json.loads((out / "run.json").read_text())["well"]["north_reference"] == "grid"
    both = "# north_reference=grid\n# well.north_reference=true\n"
    path.write_text(text.replace("# north_reference=true\n", both))  # the azimuths' wins
    with pytest.warns(InputFileWarning, match=r"well\.north_reference 'true' contradicts"):
        _, well = drift_tables.read_drift_table(path, "free_gyro", None)
    assert well.north_reference == "grid"
