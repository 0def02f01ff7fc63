"""A calibrated drift correction applies the calibration of the tool that read the survey:
the readings' own tool serial (their file's header) picks the calibration's row, a well or
stage serial that contradicts it is refused, and so is a calibration that holds no row of
it; the survey report, the fleet page and a batch's ledger state the estimate applied —
driven through ``gyropipe run``, ``gyropipe batch`` and ``gp.run`` with files written to a
temporary directory."""

from __future__ import annotations

import contextlib
import datetime as dt
import itertools
import json
import re
import sqlite3
from html import unescape
from pathlib import Path

import numpy as np
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
  - id: summary
    uses: export
    inputs: {trajectory: trajectory.trajectory, drift: drift.readings}
    with: {writer: json_summary, filename: summary.json}
  - id: report
    uses: report
    inputs:
      trajectory: trajectory.trajectory
      drift: drift.readings
      calibration: cal.calibration_result
    with: {formats: [html]}
"""
CALIBRATED = dt.date(2026, 5, 12)
HEAT = pa.field("temperature", pa.float64(), metadata={"unit": "degC"})


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
    """The pipeline, free-gyro readings of tool IG50-1 (its serial in the CSV header, 1 h
    long) and calibration results made by ``pipelines/calibration.yaml`` (1.9 h long,
    recorded on 2026-05-12): of both tools, and of IG50-2 alone."""
    tmp = tmp_path_factory.mktemp("match")
    (tmp / "pipeline.yaml").write_text(PIPELINE)
    readings = tmp / "readings.csv"
    write_csv(simulate_free_gyro(survey()), readings, WellMetadata(tool_serial="IG50-1"))
    made = {"pipeline": tmp / "pipeline.yaml", "readings": readings}
    for name, tools in (("both", ["IG50-1", "IG50-2"]), ("other", ["IG50-2"])):
        plans = [
            CalibrationPlan(
                instrument=t,
                seed=k,
                reading_noise=0.5,
                drift=Drift(rate=RATES[t]),
                reading_interval=120.0,  # 1.9 h, the 1 h survey's drift within its span
            )
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
    return float(calibration_row(calibration, serial)["drift_deg_h"])


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
    assert (
        "warning: stage 'drift': drift calibration: the survey's tool serial is stated nowhere"
        in cli.stderr
    )


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


@pytest.mark.parametrize("dated", [False, True], ids=["undated", "dated"])
def test_the_calibration_header_is_not_the_surveys(
    files: dict[str, Path], tmp_path: Path, dated: bool
):
    """The calibration result's file carries its own header — recorded on the stand on
    2026-05-12, tool IG50-2 (the last instrument of its run) — which is the calibration's,
    not the survey's: the run's well, summary and report keep the readings' serial and
    date (the run's survey date was the calibration's day, or a range from it to the
    survey's, and the two serials left the run's unstated)."""
    readings = tmp_path / "readings.csv"
    header = WellMetadata(
        tool_serial="IG50-1", survey_date=dt.date(2026, 11, 21) if dated else None
    )
    write_csv(simulate_free_gyro(survey()), readings, header)
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run", files["pipeline"], "--input", f"readings={readings}", "--input",
        f"calibration={files['both']}", "--out", out,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    expected = {"tool_serial": "IG50-1", "north_reference": "true"}
    if dated:
        expected["survey_date"] = "2026-11-21"
    manifest = json.loads((out / "run.json").read_text())
    assert manifest["well"] == expected
    assert "well_differs" not in manifest
    page = unescape((out / "report.html").read_text())
    survey_date = re.search(r"Survey date</dt><dd>([^<]*)", page)
    assert (survey_date.group(1) if survey_date else None) == expected.get("survey_date")
    summary = json.loads((out / "summary.json").read_text())
    assert {k: v for k, v in summary["well"].items() if v is not None} == expected
    drift = summary["drift"]  # the calibration applied, as its own file states it
    assert (drift["source"], drift["instrument"], drift["method"]) == (
        "calibration",
        "IG50-1",
        "fit",
    )
    assert drift["rate"] == selected_rate(files["both"], "IG50-1")
    assert drift["calibration_date"] == "2026-05-12"
    assert any("193 days before the survey" in c for c in drift["caveats"]) == dated
    result = gp.run(files["pipeline"], {"readings": readings, "calibration": files["both"]})
    assert result.well.tool_serial == "IG50-1" and result.well.survey_date_last is None


def test_a_calibration_of_no_stated_date_says_so(files: dict[str, Path], tmp_path: Path):
    """A calibration whose readings state no day: "not stated", never a date made up."""
    readings_csv = tmp_path / "calibration.csv"
    plan = CalibrationPlan(
        instrument="IG50-1", reading_noise=0.5, drift=Drift(rate=3.0), reading_interval=120.0
    )
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


def warnings_in(html: Path) -> dict[str, list[str]]:
    """The warning verdicts of each section of an HTML report, by section id."""
    text = html.read_text(encoding="utf-8")
    return {
        key: [unescape(v) for v in re.findall(r'<p class="verdict warn">(.*?)</p>', body)]
        for key, body in re.findall(r'<section id="([\w-]+)">(.*?)</section>', text, re.S)
    }


def calibrated(
    tmp_path: Path, name: str, plan: CalibrationPlan, day: dt.date | None, heat: tuple = ()
) -> Path:
    """A calibration result made by ``pipelines/calibration.yaml`` from readings simulated
    by ``plan``, recorded on ``day``, at temperatures rising evenly over ``heat`` (°C)."""
    table = simulate_calibration(plan)
    if heat:
        table = table.append_column(HEAT, pa.array(np.linspace(*heat, table.num_rows)))
    readings_csv = tmp_path / f"{name}.csv"
    write_csv(table, readings_csv, WellMetadata(survey_date=day))
    gyropipe_cli(
        "run", ROOT / "pipelines" / "calibration.yaml", "--input", readings_csv,
        "--out", tmp_path / name, "--set", "report.formats=[html]", check=True,
    )  # fmt: skip
    return tmp_path / name / "drift.result.parquet"


def surveyed(tmp_path: Path, day: dt.date | None, heat: tuple = ()) -> Path:
    """Free-gyro readings of IG50-1 (1 h) surveyed on ``day``, at temperatures rising
    evenly over ``heat`` (°C), as a CSV file."""
    table = simulate_free_gyro(survey())
    if heat:
        table = table.append_column(HEAT, pa.array(np.linspace(*heat, table.num_rows)))
    path = tmp_path / "readings.csv"
    write_csv(table, path, WellMetadata(tool_serial="IG50-1", survey_date=day))
    return path


def corrected(files: dict[str, Path], readings: Path, calibration: Path, out: Path, *extra: str):
    return run({**files, "readings": readings, "given": calibration}, "given", out, *extra)


def test_a_survey_longer_than_its_calibration_is_warned(files: dict[str, Path], tmp_path: Path):
    """A 0.5 h calibration applied to a 1 h survey: the rate is extrapolated in time —
    warned on the command line, in the drift section and in the summary (it was applied
    without a word)."""
    plan = CalibrationPlan(instrument="IG50-1", reading_noise=0.5, reading_interval=30.0)
    short = calibrated(tmp_path, "short", plan, None)
    span_h = np.ptp(simulate_calibration(plan).column("time").to_numpy()) / 3600
    result = corrected(files, files["readings"], short, tmp_path / "out")
    assert result.returncode == 0, result.stderr
    said = f"the survey's readings span 1.00 h, beyond the {span_h:.2f} h over which the "
    assert f"warning: stage 'drift': drift calibration: {said}" in result.stderr
    found = warnings_in(tmp_path / "out" / "report.html")
    expected = f"Drift calibration: {said}calibration of IG50-1 saw its drift: the drift rate "
    for section in ("summary", "drift"):
        (verdict,) = found[section]
        assert verdict == expected + "is extrapolated in time.", section
    readings = pq.read_table(tmp_path / "out" / "drift.readings.parquet")
    assert readings.column("drift_rate")[0].as_py() == selected_rate(short, "IG50-1")


def test_a_survey_hotter_than_its_calibration_is_warned(files: dict[str, Path], tmp_path: Path):
    """Calibrated at 20–25 °C, surveyed at 20–85 °C (both in the CSV files' temperature
    columns): extrapolated in temperature; surveyed within 21–24 °C: no caveat."""
    plan = CalibrationPlan(instrument="IG50-1", reading_noise=0.5, reading_interval=120.0)
    cal = calibrated(tmp_path, "cal", plan, None, heat=(20.0, 25.0))
    row = pq.read_table(cal).to_pylist()[0]
    assert (row["temperature_min"], row["temperature_max"]) == (20.0, 25.0)
    hot = corrected(files, surveyed(tmp_path, None, (20.0, 85.0)), cal, tmp_path / "hot")
    assert hot.returncode == 0, hot.stderr
    assert (
        "drift calibration: the survey read temperatures of 20.0 to 85.0 °C, beyond the 20.0 "
        "to 25.0 °C of the calibration of IG50-1: the drift rate is extrapolated in temperature"
    ) in hot.stderr
    assert len(warnings_in(tmp_path / "hot" / "report.html")["summary"]) == 1
    mild = corrected(files, surveyed(tmp_path, None, (21.0, 24.0)), cal, tmp_path / "mild")
    assert mild.returncode == 0, mild.stderr
    assert "warning" not in mild.stderr
    assert warnings_in(tmp_path / "mild" / "report.html")["summary"] == []


@pytest.mark.parametrize(
    ("day", "words"),
    [(dt.date(2026, 11, 21), "193 days before"), (dt.date(2025, 12, 1), "162 days after")],
)
def test_an_old_calibration_is_warned(
    files: dict[str, Path], tmp_path: Path, day: dt.date, words: str
):
    """Calibrated 2026-05-12: a survey of 2026-11-21 is 193 days later, beyond the default
    180; one of 2025-12-01 came 162 days before it, beyond a limit of 150 days, within 180."""
    readings = surveyed(tmp_path, day)
    limit = "180" if day.year == 2026 else "150"
    flagged = corrected(
        files, readings, files["both"], tmp_path / "old",
        "--set", f"drift.max_calibration_age_days={limit}",
    )  # fmt: skip
    assert flagged.returncode == 0, flagged.stderr
    assert (
        f"the calibration of IG50-1 (2026-05-12) was recorded {words} the survey, beyond "
        f"the {limit} days a calibration is taken to hold"
    ) in flagged.stderr
    assert len(warnings_in(tmp_path / "old" / "report.html")["summary"]) == 1
    quiet = corrected(
        files, readings, files["both"], tmp_path / "new",
        "--set", "drift.max_calibration_age_days=200",
    )  # fmt: skip
    assert quiet.returncode == 0, quiet.stderr
    assert "warning" not in quiet.stderr


def test_caveats_refuse_when_told(files: dict[str, Path], tmp_path: Path):
    readings = surveyed(tmp_path, dt.date(2026, 11, 21))
    result = corrected(
        files, readings, files["both"], tmp_path / "out", "--set",
        "drift.calibration_caveats=refuse",
    )  # fmt: skip
    assert result.returncode != 0
    assert "CalibrationRangeError: the drift calibration: the calibration of IG50-1" in (
        result.stderr
    )
    assert "Traceback" not in result.output and not (tmp_path / "out").exists()


def test_a_calibration_date_that_is_no_day_is_refused(files: dict[str, Path], tmp_path: Path):
    table = pq.read_table(files["both"])
    at = table.column_names.index("calibration_date")
    bad = table.set_column(
        at, table.schema.field(at), pa.array(["12/05/2026"] * table.num_rows, pa.string())
    )
    pq.write_table(bad, tmp_path / "bad.parquet")
    readings = surveyed(tmp_path, dt.date(2026, 11, 21))
    result = corrected(files, readings, tmp_path / "bad.parquet", tmp_path / "out")
    assert result.returncode != 0
    assert "states its date as '12/05/2026', not a day (2026-05-12)" in result.stderr
    assert "Traceback" not in result.output


def test_the_fleet_page_states_the_calibration_and_its_caveats(
    files: dict[str, Path], tmp_path: Path
) -> None:
    """A batch of two wells corrected with IG50-1's calibration, one surveyed 193 days after
    it: the fleet page's drift cell names the instrument and, for that well, the age caveat
    (it showed the rate alone: the caveat was in the well's report only)."""
    fresh = tmp_path / "fresh.csv"
    old = tmp_path / "old.csv"
    for path, day in ((fresh, dt.date(2026, 6, 1)), (old, dt.date(2026, 11, 21))):
        header = WellMetadata(tool_serial="IG50-1", survey_date=day)
        write_csv(simulate_free_gyro(survey()), path, header)
    manifest = tmp_path / "wells.csv"
    manifest.write_text(
        f"well_id,readings,calibration\nFRESH,{fresh},{files['both']}\nOLD,{old},{files['both']}\n"
    )
    out = tmp_path / "batch"
    result = gyropipe_cli(
        "batch", files["pipeline"], "--manifest", manifest, "--out", out, "--workers", "1"
    )
    assert result.returncode == 0, result.output
    rows = fleet_rows(out)
    assert "IG50-1:" in rows["OLD"] and "IG50-1:" in rows["FRESH"]
    assert "⚠" in rows["OLD"] and "193 days before the survey" in rows["OLD"]
    assert "⚠" not in rows["FRESH"]


def fleet_rows(out: Path) -> dict[str, str]:
    """Each well's row of a batch's fleet page, as text, by well."""
    raw = (out / "fleet.html").read_text(encoding="utf-8")
    rows = {}
    for row in re.findall(r'<tr class="s-[a-z]+">(.*?)</tr>', raw, re.S):
        text = " ".join(unescape(re.sub(r"<[^>]+>", " ", row)).split())
        rows[text.split()[0]] = text
    return rows


def calibration_row(calibration: Path, serial: str) -> dict:
    """The selected estimate of instrument ``serial`` in a calibration result file."""
    rows = pq.read_table(calibration).to_pylist()
    return next(r for r in rows if r["instrument"] == serial and r["selected"])


def block(status: str, well: str) -> str:
    """``well``'s line of ``gyropipe status`` and the lines under it, joined as one text."""
    lines = status.splitlines()
    start = next(i for i, line in enumerate(lines) if line.split(" ")[0] == well)
    under = itertools.takewhile(lambda line: line.startswith(" "), lines[start + 1 :])
    return " ".join(" ".join(line.split()) for line in (lines[start], *under))


def test_the_ledger_records_the_calibration_applied(files: dict[str, Path], tmp_path: Path):
    """A batch of three wells: ONE and TWO surveyed by IG50-1 and IG50-2 (their readings'
    headers) with one calibration file of both tools, BLANK by a tool its readings do not
    name with a calibration of IG50-2 alone (applied with a caveat; the run's well states
    no serial, and the ledger named the run's serial, none, as the tool). Each well's ledger row (read with
    sqlite3), ``gyropipe status`` and ``history`` name the instrument applied at its rate and
    σ in the calibration file; the calibration entries name no tool; the fleet page shows
    the rate applied, not the other tool's estimate beside it. Corrected with a given rate,
    a well records that rate and no instrument."""
    two, blank = tmp_path / "two.csv", tmp_path / "blank.csv"
    write_csv(simulate_free_gyro(survey()), two, WellMetadata(tool_serial="IG50-2"))
    write_csv(simulate_free_gyro(survey()), blank, WellMetadata())
    pipeline = tmp_path / "pipeline.yaml"  # the calibration read is persisted too
    read = "uses: read_calibration_result\n"
    assert read in PIPELINE
    pipeline.write_text(PIPELINE.replace(read, f"{read}    persist: [calibration_result]\n"))
    manifest = tmp_path / "wells.csv"
    manifest.write_text(
        "well_id,readings,calibration\n"
        f"ONE,{files['readings']},{files['both']}\n"
        f"TWO,{two},{files['both']}\n"
        f"BLANK,{blank},{files['other']}\n"
    )
    out = tmp_path / "batch"
    result = gyropipe_cli("batch", pipeline, "--manifest", manifest, "--out", out)
    assert result.returncode == 0, result.output
    assert "tool_serial" not in json.loads((out / "BLANK" / "run.json").read_text())["well"]

    status = gyropipe_cli("status", out).stdout
    listed = json.loads(gyropipe_cli("status", out, "--json").stdout)["wells"]
    document = {w["well"]: w["drift"] for w in listed}
    page = fleet_rows(out)
    stated_nowhere = (
        "the survey's tool serial is stated nowhere: the calibration's one instrument, "
        "'IG50-2', was taken for the survey's tool"
    )
    applied = {  # the survey undated, shorter than the calibrations, of no temperatures
        "ONE": ("IG50-1", "IG50-2", files["both"], []),
        "TWO": ("IG50-2", "IG50-1", files["both"], []),
        "BLANK": ("IG50-2", "IG50-1", files["other"], [stated_nowhere]),
    }
    for well, (serial, other, calibration, caveats) in applied.items():
        row = calibration_row(calibration, serial)
        (entry,), (drift,) = ledger_columns(out, well, "calibration", "drift")
        assert "tool_serial" not in entry and entry["input"] == "calibration"
        assert drift == {
            "stage": "drift",
            "port": "readings",
            "instrument": serial,
            "source": "calibration",
            "method": row["method"],
            "label": row["label"],
            "rate_deg_h": row["drift_deg_h"],  # the same doubles as the file's
            "sigma_deg_h": row["sigma_deg_h"],
            "calibration_date": CALIBRATED.isoformat(),
            "verdict": row["verdict"],
            "caveats": caveats,
        }
        assert document[well] == [drift]
        said = (
            f"drift applied (drift.readings): {row['drift_deg_h']:.4f} ± "
            f"{row['sigma_deg_h']:.4f} deg/h, calibration of {serial} ({row['method']}, "
            f"2026-05-12, {row['verdict']})"
        )
        assert said in block(status, well)
        assert f"  {said}" in gyropipe_cli("history", well, "--dir", out).stdout
        assert f"{serial}:" in page[well] and other not in page[well]

    given = tmp_path / "given"
    command = ("batch", pipeline, "--manifest", manifest, "--out", given)
    rate = ("--set", "drift.source=given", "--set", "drift.drift_rate=2.5")
    assert gyropipe_cli(*command, *rate).returncode == 0
    (entry,), drift = ledger_columns(given, "ONE", "calibration", "drift")
    assert entry["instruments"] == ["IG50-1", "IG50-2"]  # read, not applied
    assert drift == [
        {
            "stage": "drift",
            "port": "readings",
            "instrument": None,
            "source": "given",
            "method": None,
            "label": None,
            "rate_deg_h": 2.5,
            "sigma_deg_h": 0.0,  # drift_sigma unset
            "calibration_date": None,
            "verdict": None,
            "caveats": [],
        }
    ]
    text = block(gyropipe_cli("status", given).stdout, "ONE")
    assert "drift applied (drift.readings): 2.5000 ± 0.0000 deg/h, a given rate" in text
    assert "IG50" not in text and "IG50" not in fleet_rows(given)["ONE"]


def ledger_columns(out: Path, well: str, *columns: str) -> list:
    """The JSON ``columns`` of ``well``'s latest run in ``out``'s ledger (plain sqlite3)."""
    with contextlib.closing(sqlite3.connect(out / "ledger.sqlite")) as db:
        found = db.execute(
            f"SELECT {', '.join(columns)} FROM runs WHERE well = ? ORDER BY id DESC", (well,)
        ).fetchone()
    return [json.loads(value) for value in found]
