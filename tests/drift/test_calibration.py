"""Drift calibration (seed 000) against its simulator: Monte Carlo of the estimates and their
σ, the accuracy-gain claim, the power of the linearity test, other layouts of the readings,
and the calibration pipeline on the bundled example."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from scipy import stats

import pipeline as gp
from pipeline.drift.calibration import (
    LINEAR,
    NON_LINEAR,
    UNTESTED,
    CalibrationOptions,
    calibrate,
)
from pipeline.drift.tables import CalibrationReadings
from pipeline.errors import GyropipeError, InputFileError
from pipeline.graph import build_plan
from pipeline.io import drift_tables
from pipeline.plugins import load_registry
from pipeline.registry import PluginInfo, ReaderDef, Registry, StageDef
from pipeline.runner import run_plan
from pipeline.sim.calibration import CalibrationPlan, schedule, simulate_calibration
from pipeline.sim.spec import Drift
from pipeline.spec import load_spec
from pipeline.stages import drift as drift_plugin
from tests_support import ROOT

RUNS = 400
RATE = 4.0  # deg/h, the plan's default


def drift_registry() -> Registry:
    """The real registry, with the drift plugin added unless it is already built in."""
    registry = load_registry()
    if "calibrate_drift" not in registry.stages:
        plugin = PluginInfo("builtin.drift", "test", builtin=True)
        registry.plugins[plugin.name] = plugin
        drift_plugin.gyropipe_register_stages(lambda s: registry.add(s, plugin, StageDef))
    if "drift_tables" not in registry.readers:
        plugin = PluginInfo("builtin.drift_tables", "test", builtin=True)
        registry.plugins[plugin.name] = plugin
        drift_tables.gyropipe_register_readers(lambda r: registry.add(r, plugin, ReaderDef))
    assert not registry.problems, registry.problems
    return registry


def monte_carlo(runs: int, **plan: object) -> dict[tuple[str, str], np.ndarray]:
    """(method, label) → array (runs, 3) of drift °/h, σ °/h, p-value."""
    out: dict[tuple[str, str], list[tuple[float, float, float]]] = {}
    for seed in range(runs):
        result, _ = calibrate(
            simulate_calibration(CalibrationPlan(seed=seed, **plan)),  # type: ignore[arg-type]
            CalibrationOptions(),
        )
        d = result.to_pydict()
        columns = (d["method"], d["label"], d["drift_deg_h"], d["sigma_deg_h"], d["p_value"])
        for row in zip(*columns, strict=True):
            out.setdefault((row[0], row[1]), []).append(row[2:])
    return {k: np.array(v) for k, v in out.items()}


@pytest.fixture(scope="module")
def linear_runs() -> dict[tuple[str, str], np.ndarray]:
    return monte_carlo(RUNS)


def test_every_estimate_recovers_a_linear_drift_within_its_predicted_sigma(linear_runs):
    methods = {method for method, _ in linear_runs}
    assert methods == {"adjacent", "pair", "mean", "grouped", "fit", "traditional"}
    for (method, label), runs in linear_runs.items():
        z = (runs[:, 0] - RATE) / runs[:, 1]
        assert 0.85 < z.std() < 1.15, (method, label, z.std())
        assert abs(z.mean()) < 0.15, (method, label, z.mean())
        # the σ formula (mean predicted) matches the Monte Carlo spread of the estimates
        assert runs[:, 1].mean() == pytest.approx(runs[:, 0].std(), rel=0.12), (method, label)


def test_sigma_formulas_match_the_paper_for_complete_series(linear_runs):
    plan = CalibrationPlan()
    series, _, time = schedule(plan)
    n = len(plan.set_azimuths)
    mid = np.array([time[series == i].mean() for i in range(1, plan.series + 1)]) / 3600
    sigma_mean = plan.reading_noise / np.sqrt(n)  # σ of a series mean
    adjacent = np.sqrt(2) * sigma_mean / (mid[1] - mid[0])  # σ² = σ_i² + σ_{i−1}², ÷ Δt
    grouped = np.sqrt(2 * sigma_mean**2 / 2) / ((mid[2] + mid[3] - mid[0] - mid[1]) / 2)
    traditional = np.sqrt(2) * plan.reading_noise / 0.5  # two readings 30 min apart
    for key, expected in (
        (("adjacent", "1-2"), adjacent),
        (("grouped", "1+2 vs 3+4"), grouped),
        (("traditional", "readings at 0° t=30 s and t=1830 s"), traditional),
    ):
        # σ̂ comes from 36 degrees of freedom: E[σ̂] ≈ σ (1 − 1/(4·36))
        assert linear_runs[key][:, 1].mean() == pytest.approx(expected, rel=0.03), key


def test_accuracy_gain_claim_of_seed_000(linear_runs):
    """At equal time separation two series means beat two single readings by √n, not by
    the paper's √(n(n−1)/2): series 1 and 3 are 30 min apart, like the control readings."""
    n = 13
    trad = linear_runs[("traditional", "readings at 0° t=30 s and t=1830 s")][:, 0]
    pair = linear_runs[("pair", "1-3")][:, 0]
    measured = trad.std() / pair.std()
    assert measured == pytest.approx(np.sqrt(n), rel=0.1)
    assert measured < 0.5 * np.sqrt(n * (n - 1) / 2)
    result, _ = calibrate(simulate_calibration(CalibrationPlan()), CalibrationOptions())
    row = result.filter(pa.compute.equal(result.column("label"), "1-3")).to_pylist()[0]
    assert row["gain"] == pytest.approx(np.sqrt(n))  # predicted: equal intervals, same σ̂
    assert row["gain_claimed"] == pytest.approx(np.sqrt(78))


def test_linearity_test_has_its_size_and_predicted_power(linear_runs):
    rejected = (linear_runs[("fit", "1…4")][:, 2] < 0.01).mean()
    assert rejected < 0.03  # size 1 %: 4 expected of 400
    curvature = 40.0  # deg/h²
    runs = monte_carlo(RUNS, drift=Drift(rate=RATE, curvature=curvature))
    power = (runs[("fit", "1…4")][:, 2] < 0.01).mean()
    # non-central F: λ = |residual of the true series means about their line|² / σ_m²
    plan = CalibrationPlan()
    series, _, time = schedule(plan)
    hours = time / 3600
    means = np.array([np.mean(curvature * hours[series == i] ** 2) for i in range(1, 5)])
    mids = np.array([hours[series == i].mean() for i in range(1, 5)])
    design = np.stack([np.ones(4), mids], axis=1)
    resid = means - design @ np.linalg.lstsq(design, means, rcond=None)[0]
    lam = resid @ resid / (plan.reading_noise**2 / 13)
    dof = 52 - 16  # readings − (4 series + 12 pattern terms; within-series drift confounded)
    predicted = stats.ncf.sf(stats.f.isf(0.01, 2, dof), 2, dof, lam)
    assert 0.5 < predicted < 0.85
    assert power == pytest.approx(predicted, abs=3 * np.sqrt(predicted * (1 - predicted) / RUNS))


def test_verdict_names_a_gross_non_linearity():
    readings = simulate_calibration(
        CalibrationPlan(drift=Drift(rate=RATE, curvature=120.0), reading_noise=2.0)
    )
    result, _ = calibrate(readings, CalibrationOptions())
    assert set(result.column("verdict").to_pylist()) == {NON_LINEAR}
    assert result.column("p_value")[0].as_py() < 1e-6


def test_alternate_sweeps_and_per_series_times():
    """Reversed sweeps separate the within-series drift from the azimuth pattern; times may
    be given per series (readings evenly spread, in row order)."""
    plan = CalibrationPlan(sweep="alternate", seed=3, reading_noise=1.0)
    readings = simulate_calibration(plan)
    series = readings.column("series").to_numpy()
    step = len(plan.set_azimuths) * plan.reading_interval
    start = (series - 1) * (step + plan.series_gap)
    per_series = readings.drop(["time"]).append_column(
        CalibrationReadings.compiled().schema().field("series_start"), pa.array(start * 1.0)
    )
    per_series = per_series.append_column(
        CalibrationReadings.compiled().schema().field("series_end"), pa.array(start + step * 1.0)
    )
    CalibrationReadings.validate_table(per_series)
    for table in (readings, per_series):
        result, series_table = calibrate(table, CalibrationOptions(use="grouped"))
        row = result.filter(result.column("selected")).to_pylist()[0]
        assert row["method"] == "grouped"
        assert abs(row["drift_deg_h"] - RATE) < 3 * row["sigma_deg_h"]
        assert row["reading_sigma"] == pytest.approx(1.0, rel=0.3)
        assert series_table.num_rows == 4


def test_unbalanced_series_keep_unbiased_estimates_and_sigma():
    """A missing reading leaves the azimuth pattern in the plain mean: it is removed first."""
    z = []
    for seed in range(150):
        readings = simulate_calibration(CalibrationPlan(seed=seed))
        keep = np.ones(readings.num_rows, dtype=bool)
        keep[[3, 20, 40]] = False  # three readings of different series and azimuths lost
        result, series = calibrate(readings.filter(pa.array(keep)), CalibrationOptions())
        fit = result.filter(result.column("selected")).to_pylist()[0]
        z.append((fit["drift_deg_h"] - RATE) / fit["sigma_deg_h"])
    assert series.column("readings").to_pylist() == [12, 12, 13, 12]
    assert 0.8 < np.std(z) < 1.2 and abs(np.mean(z)) < 0.25


def test_errors_given_directly_several_instruments_and_serial_fallback():
    a = simulate_calibration(CalibrationPlan(instrument="A-1", seed=1))
    b = simulate_calibration(CalibrationPlan(instrument="B-2", seed=2, drift=Drift(rate=-3.0)))
    error = (
        (a.column("measured_azimuth").to_numpy() - a.column("set_azimuth").to_numpy() + 180) % 360
    ) - 180
    a = a.drop(["measured_azimuth"]).append_column(
        CalibrationReadings.compiled().schema().field("azimuth_error"), pa.array(error)
    )
    b = b.drop(["instrument"]).append_column("instrument", pa.nulls(b.num_rows, pa.string()))
    both = pa.concat_tables([a, b], promote_options="default")
    result, _ = calibrate(both, CalibrationOptions(), tool_serial="B-2")
    fits = {r["instrument"]: r for r in result.to_pylist() if r["selected"]}
    assert set(fits) == {"A-1", "B-2"}
    assert abs(fits["B-2"]["drift_deg_h"] + 3.0) < 3 * fits["B-2"]["sigma_deg_h"]
    assert fits["A-1"]["drift_deg_min"] == pytest.approx(fits["A-1"]["drift_deg_h"] / 60)


def test_too_few_series_are_reported():
    result, _ = calibrate(
        simulate_calibration(CalibrationPlan(series=2)), CalibrationOptions(use="grouped")
    )
    assert set(result.column("method").to_pylist()) == {"adjacent", "fit", "traditional"}
    assert result.filter(result.column("selected")).column("method").to_pylist() == ["fit"]
    assert set(result.column("verdict").to_pylist()) == {UNTESTED}
    with pytest.raises(ValueError, match="at least two series"):
        calibrate(simulate_calibration(CalibrationPlan(series=1)), CalibrationOptions())


def test_calibration_pipeline_on_the_bundled_example(tmp_path: Path):
    registry = drift_registry()
    plan = build_plan(load_spec(ROOT / "pipelines" / "calibration.yaml"), registry)
    run_plan(
        plan,
        registry,
        inputs={"calibration": ROOT / "examples" / "calibration-ig50.csv"},
        out_dir=tmp_path,
    )
    result = pq.read_table(tmp_path / "drift.result.parquet")
    fit = result.filter(result.column("selected")).to_pylist()[0]
    assert fit["instrument"] == "IG50-0417"  # from the file's well.tool_serial line
    assert fit["verdict"] == LINEAR
    assert abs(fit["drift_deg_h"] - RATE) < 3 * fit["sigma_deg_h"]
    series = pq.read_table(tmp_path / "drift.series.parquet")
    # the file gives time in minutes: mid-times of one-a-minute sweeps, 15 min apart
    assert series.column("mid_time").to_pylist() == pytest.approx([390, 1290, 2190, 3090])
    assert (tmp_path / "drift-calibration.csv").exists()


def test_csv_reader_names_the_problem(tmp_path: Path):
    path = tmp_path / "cal.csv"
    path.write_text("series,set_azimuth,measured_azimuth[deg],time[s]\n1,0,1.0,30\n")
    with pytest.raises(InputFileError, match=r"cal.csv:1 \(column 'set_azimuth'\).*unit"):
        drift_tables.read_drift_table(path, "calibration", None)
    path.write_text("series,set_azimuth[deg],time[fortnight]\n1,0,30\n")
    with pytest.raises(InputFileError, match="unknown unit 'fortnight'"):
        drift_tables.read_drift_table(path, "calibration", None)
    path.write_text("# well.tool_serial=X\nseries,set_azimuth[deg],azimuth_error[deg]\n1,0,x\n")
    with pytest.raises(InputFileError, match=r"cal.csv:3 \(column 'azimuth_error'\): not a number"):
        drift_tables.read_drift_table(path, "calibration", None)
    for cell in ("1e999", "-inf", "nan"):
        path.write_text(f"series,set_azimuth[deg],azimuth_error[deg]\n1,0,{cell}\n")
        with pytest.raises(
            InputFileError, match=r"cal.csv:2 \(column 'azimuth_error'\): not a finite number"
        ):
            drift_tables.read_drift_table(path, "calibration", None)
    path.write_text("series,set_azimuth[deg],azimuth_error[deg],azimuth_error[rad]\n1,0,2,0.1\n")
    with pytest.raises(  # once the last of them was read, whatever its header said
        InputFileError, match=r"cal.csv:1 \(column 'azimuth_error\[rad\]'\).*appears twice"
    ):
        gp.read(path, kind="calibration")
    path.write_text("series,set_azimuth[rad],azimuth_error[deg],extra\n1,3.14159265358979,2,z\n")
    table, _ = drift_tables.read_drift_table(path, "calibration", None)
    assert table.column("set_azimuth")[0].as_py() == pytest.approx(180.0)
    assert table.column("source_line").to_pylist() == [2]


def test_per_series_variances_give_honest_sigma():
    """The paper's per-series variances (about 9 degrees of freedom each): normalised
    errors a little wider than 1, as Student's t predicts."""
    z: dict[str, list[float]] = {"adjacent": [], "fit": []}
    for seed in range(300):
        result, series = calibrate(
            simulate_calibration(CalibrationPlan(seed=seed)), CalibrationOptions(variance="series")
        )
        for row in result.to_pylist():
            if row["method"] in z and row["label"] in ("1-2", "1…4"):
                z[row["method"]].append((row["drift_deg_h"] - RATE) / row["sigma_deg_h"])
    for values in z.values():
        assert 0.9 < np.std(values) < 1.2 and abs(np.mean(values)) < 0.15
    assert len(set(series.column("residual_std").to_pylist())) == 4  # one σ per series


@pytest.mark.parametrize("marker", ["-999.25", "999.25", "-9999.25", ""])
def test_a_null_marker_reading_is_no_reading(tmp_path: Path, marker: str):
    lines = (ROOT / "examples" / "calibration-ig50.csv").read_text().splitlines()
    assert lines[7] == "1,30,27.8,1.5"  # the reading at set azimuth 30°, left unread
    path = tmp_path / "cal.csv"
    path.write_text("\n".join([*lines[:7], f"1,30,{marker},1.5", *lines[8:]]) + "\n")
    readings = gp.read(path, kind="calibration")
    assert readings["measured_azimuth"].isna().tolist()[:3] == [False, True, False]
    with pytest.raises(GyropipeError, match="row 1: give azimuth_error or measured_azimuth"):
        gp.calibrate_drift(readings)  # once fitted with a measured azimuth of -999.25°


@pytest.mark.parametrize(("cell", "replaced"), [("27.8", "2_7.8"), ("1,30", "1_0,30")])
def test_digit_grouping_is_no_number_in_a_calibration_file(
    tmp_path: Path, cell: str, replaced: str
) -> None:
    """Python's float and int read '2_7.8' as 27.8 and '1_0' as 10; no export writes one: a
    mistyped cell, refused at its line and column."""
    from tests_support import gyropipe_cli

    source = ROOT / "examples" / "calibration-ig50.csv"
    lines = source.read_text().splitlines()
    row = next(i for i, line in enumerate(lines) if line.startswith("1,30,"))
    lines[row] = lines[row].replace(cell, replaced, 1)
    bad = tmp_path / "calibration.csv"
    bad.write_text("\n".join(lines) + "\n")
    pipeline = ROOT / "pipelines" / "calibration.yaml"
    result = gyropipe_cli("run", pipeline, "--input", bad, "--out", tmp_path / "out")
    assert result.returncode != 0 and not (tmp_path / "out").exists()
    assert (
        f"{bad}:{row + 1}" in result.stderr
        and f"not a number: {replaced.split(',')[0]!r}" in result.stderr
    )
