"""A calibrated drift correction applies the calibration of the tool that read the survey:
the readings' own tool serial (their file's header) picks the calibration's row, a well or
stage serial that contradicts it is refused, and so is a calibration that holds no row of
it; the survey report states the estimate applied — driven through ``gyropipe run`` and
``gp.run`` with files written to a temporary directory."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from pipeline.errors import StageError, SurveyCheckWarning
from pipeline.io.csv import write_csv
from pipeline.sim.calibration import CalibrationPlan, simulate_calibration
from pipeline.sim.freegyro import simulate_free_gyro
from pipeline.sim.spec import Drift, SimulationSpec
from pipeline.well import WellMetadata
from tests_support import ROOT, gyropipe_cli, tables_of

RATES = {"IG50-1": 3.0, "IG50-2": -6.0}  # deg/h: each tool's own drift on the stand

PIPELINE = """\
name: free-gyro-calibrated
version: "1.0"
inputs:
  readings: {description: free-gyro readings}
  calibration: {description: drift calibration result}
well:
  north_reference: "true"
stages:
  - id: read
    uses: read_free_gyro
  - id: cal
    uses: read_calibration_result
  - id: drift
    uses: correct_drift
    inputs: {readings: read.free_gyro, calibration: cal.calibration_result}
    with: {source: calibration, reading_sigma: 0.2}
    persist: [readings]
  - id: trajectory
    uses: minimum_curvature
    inputs: {stations: drift.stations}
  - id: report
    uses: report
    inputs:
      trajectory: trajectory.trajectory
      drift: drift.readings
      calibration: cal.calibration_result
    with: {formats: [html]}
"""
CALIBRATED = dt.date(2026, 5, 12)


def survey() -> SimulationSpec:
    return SimulationSpec.model_validate(
        {
            "name": "free",
            "seed": 7,
            "site": {"latitude": 61.25, "longitude": 73.4, "date": "2026-11-21"},
            "well": {
                "sections": [
                    {"kind": "vertical", "length": 200},
                    {"kind": "build", "dls": 3.0, "inc": 40, "azi": 37},
                    {"kind": "hold", "to_md": 900},
                ]
            },
            "tool": {"preset": "mems-vrg"},
            "survey": {
                "mode": "free_gyro",
                "every": 30,
                "reading_noise": 0.2,
                "drift": {"offset": 0.7, "rate": 3.0},
            },
        }
    )


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The pipeline, free-gyro readings of tool IG50-1 (its serial in the CSV header) and
    calibration results made by ``pipelines/calibration.yaml``: of both tools, and of
    IG50-2 alone."""
    tmp = tmp_path_factory.mktemp("match")
    (tmp / "pipeline.yaml").write_text(PIPELINE)
    readings = tmp / "readings.csv"
    write_csv(simulate_free_gyro(survey()), readings, WellMetadata(tool_serial="IG50-1"))
    made = {"pipeline": tmp / "pipeline.yaml", "readings": readings}
    for name, tools in (("both", ["IG50-1", "IG50-2"]), ("other", ["IG50-2"])):
        plans = [
            CalibrationPlan(instrument=t, seed=k, reading_noise=0.5, drift=Drift(rate=RATES[t]))
            for k, t in enumerate(tools)
        ]
        readings_csv = tmp / f"calibration-{name}.csv"
        table = pa.concat_tables([simulate_calibration(p) for p in plans])
        header = WellMetadata(tool_serial=tools[-1], survey_date=CALIBRATED)
        write_csv(table, readings_csv, header)
        out = tmp / f"cal-{name}"
        gyropipe_cli(
            "run",
            ROOT / "pipelines" / "calibration.yaml",
            "--input",
            readings_csv,
            "--out",
            out,
            "--set",
            "report.formats=[html]",
            check=True,
        )
        made[name] = out / "drift.result.parquet"
    return made


def applied_rate(out: Path) -> float:
    return pq.read_table(out / "drift.readings.parquet").column("drift_rate")[0].as_py()


def selected_rate(calibration: Path, serial: str) -> float:
    rows = pq.read_table(calibration).to_pylist()
    return next(r["drift_deg_h"] for r in rows if r["instrument"] == serial and r["selected"])


def run(files: dict[str, Path], calibration: str, out: Path, *extra: str):
    return gyropipe_cli(
        "run",
        files["pipeline"],
        "--input",
        f"readings={files['readings']}",
        "--input",
        f"calibration={files[calibration]}",
        "--out",
        out,
        *extra,
    )


def test_the_readings_serial_picks_its_own_calibration(files: dict[str, Path], tmp_path: Path):
    result = run(files, "both", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    rate = applied_rate(tmp_path / "out")
    assert rate == selected_rate(files["both"], "IG50-1")
    assert abs(rate - RATES["IG50-1"]) < 0.5  # the tool's own drift, not IG50-2's −6 °/h


def test_a_calibration_of_another_tool_only_is_refused(files: dict[str, Path], tmp_path: Path):
    # the calibration file's header names IG50-2, the readings' IG50-1: the run's well left
    # the serial unstated and the calibration's only instrument, IG50-2, was applied
    result = run(files, "other", tmp_path / "out")
    assert result.returncode != 0
    assert "holds no estimate of instrument 'IG50-1'" in result.stderr
    assert "it calibrates 'IG50-2'" in result.stderr
    assert "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "given",
    [["--well", "tool_serial=IG50-2"], ["--set", "drift.instrument=IG50-2"]],
    ids=["well", "stage"],
)
def test_a_serial_contradicting_the_readings_is_refused(
    files: dict[str, Path], tmp_path: Path, given: list[str]
):
    # the override won over the file's header: IG50-2's calibration was applied to IG50-1
    result = run(files, "both", tmp_path / "out", *given)
    assert result.returncode != 0
    assert "'IG50-1'" in result.stderr and "'IG50-2'" in result.stderr
    assert "disagree" in result.stderr
    assert "Traceback" not in result.output


def test_the_api_refuses_with_a_typed_error(files: dict[str, Path]):
    inputs = {"readings": files["readings"], "calibration": files["both"]}
    with pytest.raises(StageError, match=r"'IG50-1'.*'IG50-2'|'IG50-2'.*'IG50-1'") as caught:
        gp.run(files["pipeline"], inputs, well={"tool_serial": "IG50-2"})
    assert isinstance(caught.value.__cause__, gp.GyropipeError)
    result = gp.run(files["pipeline"], inputs, well={"tool_serial": "IG50-1"})
    rate = result.tables["drift.readings"].column("drift_rate")[0].as_py()
    assert rate == selected_rate(files["both"], "IG50-1")


def test_a_survey_of_no_stated_serial_is_flagged(files: dict[str, Path], tmp_path: Path):
    """Readings whose file states no tool serial, a calibration of one tool: its rate is
    applied, with a warning that the tool was not checked (it was applied silently)."""
    readings = tmp_path / "readings.csv"
    write_csv(simulate_free_gyro(survey()), readings, WellMetadata())
    inputs = {"readings": readings, "calibration": files["other"]}
    with pytest.warns(SurveyCheckWarning, match="'IG50-2', was taken for the survey's tool"):
        result = gp.run(files["pipeline"], inputs)
    rate = result.tables["drift.readings"].column("drift_rate")[0].as_py()
    assert rate == selected_rate(files["other"], "IG50-2")
    cli = gyropipe_cli(
        "run", files["pipeline"], "--input", f"readings={readings}", "--input",
        f"calibration={files['other']}", "--out", tmp_path / "out",
    )  # fmt: skip
    assert cli.returncode == 0, cli.stderr
    assert "warning: stage 'drift': the survey's tool serial is stated nowhere" in cli.stderr


def test_the_report_states_the_calibration_estimate_applied(files: dict[str, Path], tmp_path: Path):
    """Corrected with IG50-1's ``mean`` estimate, the report's "Drift calibration used"
    states that one — instrument, estimate, its series, rate and σ in °/h, the day it was
    recorded, its linearity verdict (it listed the selected ``fit`` rows of both tools the
    calibration holds, whichever was applied)."""
    out = tmp_path / "out"
    result = run(files, "both", out, "--set", "drift.estimate=mean")
    assert result.returncode == 0, result.stderr
    rows = pq.read_table(files["both"]).to_pylist()
    mean = next(r for r in rows if r["instrument"] == "IG50-1" and r["method"] == "mean")
    assert not mean["selected"]  # the calibration selects fit: the report must not say so
    header, *used = tables_of(out / "report.html")["calibration"]
    assert [h.strip() for h in header[:3]] == ["Instrument", "Estimate", "Series / readings"]
    (row,) = used
    assert row[0] == "IG50-1"
    assert row[1].startswith("mean: ") and row[2] == "1…4"
    assert float(row[3].replace("−", "-")) == pytest.approx(mean["drift_deg_h"], abs=5e-4)
    assert float(row[4]) == pytest.approx(mean["sigma_deg_h"], rel=0.05)
    assert row[5] == "2026-05-12" and row[6] == "linear"
    assert "IG50" not in "".join(header)


def test_a_calibration_of_no_stated_date_says_so(files: dict[str, Path], tmp_path: Path):
    """A calibration whose readings state no day: "not stated", never a date made up."""
    readings_csv = tmp_path / "calibration.csv"
    plan = CalibrationPlan(instrument="IG50-1", reading_noise=0.5, drift=Drift(rate=3.0))
    write_csv(simulate_calibration(plan), readings_csv, WellMetadata())
    cal = tmp_path / "cal"
    gyropipe_cli(
        "run", ROOT / "pipelines" / "calibration.yaml", "--input", readings_csv, "--out", cal,
        "--set", "report.formats=[html]", check=True,
    )  # fmt: skip
    files = {**files, "undated": cal / "drift.result.parquet"}
    assert pq.read_table(files["undated"]).column("calibration_date").null_count > 0
    result = run(files, "undated", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    (row,) = tables_of(tmp_path / "out" / "report.html")["calibration"][1:]
    assert row[0] == "IG50-1" and row[5] == "not stated"


def test_a_given_rate_is_stated_as_given(tmp_path: Path):
    """Corrected with a given rate: the report says where it came from beside the rate."""
    out = tmp_path / "out"
    readings = tmp_path / "readings.parquet"
    pq.write_table(simulate_free_gyro(survey()), readings)
    gyropipe_cli(
        "run", ROOT / "pipelines" / "free-gyro.yaml", "--input", readings, "--out", out,
        "--set", "drift.source=given", "--set", "drift.drift_rate=2.5",
        "--set", "report.formats=[html]", check=True,
    )  # fmt: skip
    text = (out / "report.html").read_text(encoding="utf-8")
    assert "Drift rate applied" in text and "a rate given for the run" in text
    assert "drift rate 2.500 °/h, σ 0 °/h" in text
    assert "Drift calibration used" not in text
