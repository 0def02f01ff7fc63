"""The station-math stages through the runner: method choice, interpolation, north
reference conversion — wired as a user would."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.runner import run_plan
from pipeline.spec import load_spec
from tests_support import ROOT, gyropipe_cli

PIPELINE = """
name: stations
version: 1
inputs: {stations: {}}
stages:
  - id: read
    uses: read_stations
  - id: grid
    uses: north_reference
    inputs: {stations: read}
    with: {target: grid, convergence: 2.0}
  - id: balanced
    uses: survey_method
    inputs: {stations: grid}
    with: {method: balanced_tangential}
    persist: [trajectory]
  - id: mc
    uses: survey_method
    inputs: {stations: grid}
    with: {method: minimum_curvature}
  - id: every10
    uses: interpolate_md
    inputs: {trajectory: mc}
    with: {spacing: 10.0}
    persist: [points]
"""


def test_station_stages_in_a_pipeline(tmp_path: Path):
    path = tmp_path / "p.yaml"
    path.write_text(PIPELINE)
    registry = load_registry()
    plan = build_plan(load_spec(path), registry)
    result = run_plan(
        plan,
        registry,
        inputs={"stations": ROOT / "examples" / "stations-j-well.csv"},
        out_dir=tmp_path / "out",
    )
    raw = result.tables[("read", "stations")]
    grid = result.tables[("grid", "stations")]
    assert grid.schema.field("azi").metadata[b"north_reference"] == b"grid"
    expected = (raw.column("azi").to_numpy() - 2.0) % 360
    np.testing.assert_allclose(grid.column("azi").to_numpy(), expected, atol=1e-12)
    points = pq.read_table(tmp_path / "out" / "every10.points.parquet")
    md = points.column("md").to_numpy()
    np.testing.assert_allclose(np.diff(md), 10.0)
    mc = result.tables[("mc", "trajectory")]
    at = np.searchsorted(md, mc.column("md").to_numpy()[5])
    assert md[at] == mc.column("md")[5].as_py()
    np.testing.assert_allclose(
        points.column("tvd")[at].as_py(), mc.column("tvd")[5].as_py(), atol=1e-9
    )
    balanced = pq.read_table(tmp_path / "out" / "balanced.trajectory.parquet")
    assert "build" in balanced.column_names and "turn" in balanced.column_names
    # balanced tangential differs from minimum curvature only by the ratio factor (small DLS)
    diff = np.abs(balanced.column("north").to_numpy() - mc.column("north").to_numpy()).max()
    assert 0 < diff < 1.0


def test_a_course_of_a_few_ulp_is_refused_at_its_line_through_the_cli(tmp_path: Path) -> None:
    """Fuzz finding: stations at MD 0 and 4.9e-324 m gave an infinite DLS (NumPy warned of an
    overflow, then the trajectory broke its contract); now the stations file is refused at
    the line of the repeated station, before any stage computes with it."""
    stations = tmp_path / "ulp.csv"
    stations.write_text("MD [m],INC [deg],Azimuth True [deg]\n0,0,0\n4.9e-324,1,0\n30,2,0\n")
    pipeline, out = ROOT / "pipelines/survey.yaml", tmp_path / "out"
    result = gyropipe_cli("run", str(pipeline), "--input", str(stations), "--out", str(out))
    assert result.returncode == 1, result.stderr
    assert "Warning" not in result.stderr and "Traceback" not in result.stderr, result.stderr
    assert (
        f"{stations}:3: not valid as stations (reader 'csv'): column 'md': monotonic: expected "
        "strictly increasing values, by at least 0.0005 m; 1 bad row(s), first: row 1 (line 3)"
    ) in result.stderr
