"""The export stages of the ready pipelines, run as shipped (report stages left out: the
report tests render them) on the bundled sample and on small simulated point and continuous
surveys: every export is written and parses with its independent reader."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import jsonschema
import lasio
import pyarrow.parquet as pq
import pytest
from export_support import SAMPLE, without_reports
from komle.bindings.v1411.write import witsml as wml

from pipeline.graph import build_plan
from pipeline.io.mcap.tables import read_tables
from pipeline.io.parquet import write as write_parquet
from pipeline.plugins import load_registry
from pipeline.runner import RunResult, run_plan
from pipeline.sim.spec import load_simulation
from pipeline.spec import load_spec
from pipeline.stages.simulation import simulation_tables, well_of_simulation
from tests_support import ROOT, export_tolerance

SCHEMA = json.loads((ROOT / "schemas" / "writers" / "json_summary.schema.json").read_text())
PLAN = """
name: small-{mode}
seed: 3
site:
  latitude: 61.25
  longitude: 73.4
  elevation: 54.3
  date: 2026-11-21
  magnetic: {{total_field: 59731, dip: 78.29, declination: 17.0}}
well:
  sections:
    - {{kind: vertical, length: 100}}
    - {{kind: build, dls: 3.0, inc: 20, azi: 37}}
    - {{kind: hold, to_md: 400}}
tool: {{preset: mems-vrg}}
survey: {survey}
"""
SURVEYS = {
    "point": "{mode: point, every: 100, positions: [0, 90, 180, 270, 0], dwell: 10}",
    "continuous": "{mode: continuous, start_md: 150, end_md: 300, speed: 2.0}",
}


def run_ready(name: str, inputs: dict[str, Path], tmp_path: Path) -> RunResult:
    registry = load_registry()
    plan = build_plan(load_spec(without_reports(name, tmp_path)), registry)
    return run_plan(plan, registry, inputs=inputs, out_dir=tmp_path / "out")


def simulated(mode: str, tmp_path: Path) -> Path:
    plan = tmp_path / f"{mode}.yaml"
    plan.write_text(textwrap.dedent(PLAN.format(mode=mode, survey=SURVEYS[mode])))
    spec = load_simulation(plan)
    path = tmp_path / f"{mode}-samples.parquet"
    write_parquet(simulation_tables(spec)["samples"], path, well_of_simulation(spec))
    return path


def check_common(out: Path) -> dict:
    """The LAS, WITSML and JSON exports parse with their own readers; the summary."""
    trajectory = wml.CreateFromDocument((out / "trajectory.xml").read_bytes()).trajectory[0]
    las = lasio.read(str(out / "trajectory.las"))
    summary = json.loads((out / "summary.json").read_text())
    jsonschema.validate(summary, SCHEMA)
    final = summary["surveys"][0]["final"]
    assert trajectory.trajectoryStation[-1].md.value() == final["md"]
    assert abs(las.index[-1] - final["md"]) <= export_tolerance("m", final["md"])  # at 0.1 mm
    assert trajectory.aziRef == "true north" and las.params["NREF"].value == "true"
    return summary


def test_survey_pipeline_exports(tmp_path: Path):
    result = run_ready("survey", {"stations": SAMPLE}, tmp_path)
    summary = check_common(result.out_dir)
    assert summary["qc"]["checks"][0]["check"] == "dls_limit"
    assert summary["run"]["pipeline"] == "survey"


@pytest.mark.parametrize(
    ("name", "mode"), [("point-gyro", "point"), ("continuous-gyro", "continuous")]
)
def test_gyro_pipeline_exports(tmp_path: Path, name: str, mode: str):
    result = run_ready(name, {"samples": simulated(mode, tmp_path)}, tmp_path)
    summary = check_common(result.out_dir)
    tables, _ = read_tables(result.out_dir / "processed.mcap")
    trajectory = pq.read_table(result.out_dir / "trajectory.trajectory.parquet")
    assert tables["trajectory"].column("md").equals(trajectory.column("md"))
    assert summary["qc"]["rejected_stations"] == 0
    if mode == "point":
        assert sorted(tables) == ["qc", "readings", "rejects", "stations", "trajectory"]
        assert {c["check"] for c in summary["qc"]["checks"]} >= {"gravity", "rest_gyro"}
        assert summary["surveys"][0]["uncertainty_at_td"]["confidence"] == pytest.approx(0.95)
    else:
        expected = ["qc", "readings", "rejects", "series", "stations", "trajectory"]
        assert sorted(tables) == expected
        assert {c["check"] for c in summary["qc"]["checks"]} >= {"recording_end", "rest_gyro"}
        assert tables["series"].num_rows > 10 * tables["stations"].num_rows
