"""The JSON summary: a real run's summary validated against the committed JSON Schema, its
numbers taken from the run's tables, the confidence of the ellipse recovered, QC counts of
known tables, several surveys, and the export stage's refusals."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from export_support import SAMPLE, run_yaml

from pipeline.errors import ContractViolation, StageError
from pipeline.io import json_summary
from pipeline.registry import InputFile, Provenance
from pipeline.runner import RunResult
from pipeline.tables import CheckResults, Trajectory
from pipeline.well import WellMetadata, well_of
from tests_support import ROOT, pipeline_yaml, stage, survey_stages

SCHEMA = json.loads((ROOT / "schemas" / "writers" / "json_summary.schema.json").read_text())


def load(path: Path) -> dict:
    doc = json.loads(path.read_text())
    jsonschema.validate(doc, SCHEMA)
    return doc


def test_summary_of_a_run(exports_run: RunResult):
    doc = load(exports_run.out_dir / "summary.json")
    trajectory = pq.read_table(exports_run.out_dir / "uncertainty.trajectory.parquet")
    last = {name: trajectory.column(name)[-1].as_py() for name in trajectory.column_names}
    assert doc["format"] == "gyropipe.survey-summary"
    assert doc["well"] == json.loads(well_of(trajectory).model_dump_json())
    assert doc["well"]["declination"] == 17.0 and doc["well"]["grid_convergence"] == 1.25
    manifest = json.loads((exports_run.out_dir / "run.json").read_text())
    assert doc["run"]["pipeline_sha256"] == manifest["pipeline"]["sha256"]
    assert doc["run"]["inputs"] == {"stations": manifest["inputs"]["stations"]["sha256"]}
    assert doc["north_reference"] == "grid"
    # the sample lists no positions: tied at the pipeline's default, TVD = MD = 0 at the wellhead
    tie = {"survey": None, "md": 0.0, "tvd": 0.0, "north": 0.0, "east": 0.0}
    tie |= {"source": "pipeline", "parent": None}
    assert trajectory.column("md")[0].as_py() == 0.0
    assert doc["calculation"] == {
        "method": "minimum_curvature",
        "vs_azimuth": 30.0,
        "ties": [tie],
    }
    assert doc["units"] == {
        "length": "m",
        "angle": "deg",
        "dls": "deg/30m",
        "drift_rate": "deg/h",
    }
    assert doc["station_count"] == trajectory.num_rows == 85
    (survey,) = doc["surveys"]
    assert survey["final"] == {name: last[name] for name in survey["final"]}
    assert (survey["md_start"], survey["md_end"]) == (0.0, last["md"])
    dls = trajectory.column("dls").to_numpy()
    assert survey["max_dls"] == {  # every course of the sample is 30 m: none left out
        "dls": float(dls.max()),
        "md": trajectory.column("md")[int(dls.argmax())].as_py(),
        "min_course_length": 10.0,
        "courses_not_counted": 0,
        "all_courses_short": False,
    }
    ellipse = survey["uncertainty_at_td"]
    assert ellipse["semi_major"] == last["ellipse_major"] > 1.0
    assert ellipse["sigma_vertical"] == last["sigma_v"]
    assert ellipse["semi_major_conf"] == last["ellipse_major_conf"]
    assert ellipse["confidence"] == pytest.approx(0.9, abs=1e-12)  # the stage's parameter
    results = pq.read_table(exports_run.out_dir / "dls_check.results.parquet")
    failed = results.num_rows - sum(results.column("passed").to_pylist())
    assert 0 < failed < results.num_rows  # the 2°/30 m limit fails some of the build
    assert doc["qc"] == {
        "checks": [
            {
                "check": "dls_limit",
                "evaluated": 85,
                "passed": 85 - failed,
                "failed": failed,
                "not_evaluated": 0,
            }
        ],
        "failed": failed,
        "not_evaluated": 0,
        "flagged_stations": None,
        "rejected_stations": None,
        "dropped_stations": None,
        "dropped": [],
    }


def _trajectory(surveys: list[str], md: list[float], dls: list[float]) -> pa.Table:
    n = len(md)
    columns = {
        "survey": surveys,
        "md": md,
        "inc": [10.0] * n,
        "azi": [20.0] * n,
        "tvd": md,
        "north": [0.0] * n,
        "east": [0.0] * n,
        "dogleg": [0.0] * n,
        "dls": dls,
        "vertical_section": [0.0] * n,
        "closure_distance": [0.0] * n,
        "closure_direction": [0.0] * n,
    }
    return Trajectory.compiled().make_table(columns, north_reference="magnetic")


def test_qc_counts_and_several_surveys(tmp_path: Path):
    trajectory = _trajectory(["a", "a", "b", "b", "b"], [0, 10, 0, 5, 9], [0, 1, 0, 4, 3])
    qc = pa.table(
        {
            "check": ["gravity", "gravity", "gravity", "earth_rate", "earth_rate"],
            "passed": pa.array([True, False, None, None, True]),
        }
    )
    stations = pa.table({"flags": ["", "inconsistent", "poor_azimuth,frame_mismatch", ""]})
    rejects = pa.table({"station": [7, 9], "md": [30.0, 10.0], "reason": ["too few", "mirror"]})
    verdicts = pa.table(
        {
            "station": [6, 7, 8],
            "md": [20.0, 30.0, 40.0],
            "status": ["drop", "ok", "flag"],
            "failed_checks": ["rest_gyro,gravity", "", "gravity"],
            "suspect": ["", "", ""],
            "diagnosis": ["", "", ""],
        }
    )
    path = tmp_path / "s.json"
    tables = {"trajectory": trajectory, "qc": qc, "stations": stations, "rejects": rejects,
              "qc_summary": verdicts}  # fmt: skip
    json_summary.write_tables(tables, path, WellMetadata(well="Q"), _provenance())
    doc = load(path)
    assert [(s["survey"], s["station_count"], s["md_end"]) for s in doc["surveys"]] == [
        ("a", 2, 10.0),
        ("b", 3, 9.0),
    ]
    assert doc["surveys"][1]["max_dls"] == {  # courses of 5 and 4 m: every one counted
        "dls": 4.0,
        "md": 5.0,
        "min_course_length": 10.0,
        "courses_not_counted": 0,
        "all_courses_short": True,
    }
    assert doc["surveys"][0]["uncertainty_at_td"] is None
    assert doc["north_reference"] == "magnetic" and doc["calculation"] is None
    assert doc["qc"] == {
        "checks": [
            {"check": "earth_rate", "evaluated": 1, "passed": 1, "failed": 0, "not_evaluated": 1},
            {"check": "gravity", "evaluated": 2, "passed": 1, "failed": 1, "not_evaluated": 1},
        ],
        "failed": 1,
        "not_evaluated": 2,
        "flagged_stations": 2,
        "rejected_stations": 2,
        "dropped_stations": 3,  # the validity drop at 20 m and both rejects, in MD order
        "dropped": [
            _dropped(10.0, 9, "compassing", [], "mirror"),
            _dropped(20.0, 6, "validity", ["rest_gyro", "gravity"], ""),
            _dropped(30.0, 7, "compassing", [], "too few"),
        ],
    }
    unnamed = {"trajectory": trajectory, "rejects": pa.table({"station": [7, 9]})}
    with pytest.raises(ValueError, match=r"rejects port takes .* the table wired has station$"):
        json_summary.write_tables(unnamed, path, WellMetadata(well="Q"), _provenance())
    int_flags = {"trajectory": trajectory, "stations": pa.table({"flags": [0, 4, 0, 1, 1]})}
    json_summary.write_tables(int_flags, path, WellMetadata(well="Q"), _provenance())
    assert load(path)["qc"]["flagged_stations"] == 3


def _dropped(md: float, station: int, by: str, checks: list[str], reason: str) -> dict[str, Any]:
    """A station dropped as the summary states it."""
    return {"md": md, "station": station, "dropped_by": by, "checks": checks, "reason": reason}


def _provenance() -> Provenance:
    """A run's provenance as the runner builds it."""
    return Provenance(
        pipeline="p",
        pipeline_version="1",
        pipeline_file="p.yaml",
        pipeline_sha256="0" * 64,
        gyropipe="0.1.0",
        plugins={"builtin.survey": "0.1.0"},
        inputs={"stations": InputFile("s.csv", "1" * 64, 10)},
        started=dt.datetime(2026, 11, 21, 12, 0, tzinfo=dt.UTC),
        stages=(),
    )


def test_write_summarises_one_trajectory_and_refuses_other_tables(tmp_path: Path):
    path = tmp_path / "one.json"
    json_summary.write(_trajectory(["x", "x"], [0.0, 30.0], [0.0, 2.5]), path, WellMetadata())
    doc = load(path)
    assert doc["run"] is None and doc["qc"] is None
    assert doc["surveys"][0]["final"]["md"] == 30.0
    checks = CheckResults.compiled().make_table(
        {
            "check": ["c"],
            "row": [0],
            "md": [1.0],
            "value": [np.nan],
            "limit": [1.0],
            "unit": [""],
            "passed": [True],
        }
    )
    with pytest.raises(ContractViolation, match="column 'inc': present"):
        json_summary.write(checks, path, WellMetadata())
    with pytest.raises(ValueError, match="wire the port 'trajectory'"):
        json_summary.write_tables({"qc": checks}, path, WellMetadata(), _provenance())


def test_export_stage_refuses_single_table_writers_and_no_tables(tmp_path: Path):
    head = survey_stages()
    trajectory = {"trajectory": "trajectory.trajectory"}
    csv_export = pipeline_yaml([*head, stage("out", "export", trajectory, writer="csv")])
    with pytest.raises(StageError, match="writer 'csv' writes one table: use the write stage"):
        run_yaml(csv_export, {"stations": SAMPLE}, tmp_path / "a")
    nothing = pipeline_yaml([*head, stage("out", "export", writer="json_summary")])
    with pytest.raises(StageError, match="wire at least one of the ports trajectory, stations"):
        run_yaml(nothing, {"stations": SAMPLE}, tmp_path / "b")
    assert not (tmp_path / "a").exists()  # a failed run publishes nothing
