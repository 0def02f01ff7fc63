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
from tests_support import ROOT

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
