"""Runs shared by the export tests: real pipelines on the bundled sample through the runner."""

from __future__ import annotations

import textwrap
from pathlib import Path

import yaml

from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.runner import RunResult, run_plan
from pipeline.spec import load_spec
from pipeline.well import WellMetadata
from tests_support import ROOT

SAMPLE = ROOT / "examples" / "stations-j-well.csv"

EXPORTS = """
name: exports
version: "1.0"
inputs:
  stations: {description: survey stations}
well:
  north_reference: "true"
stages:
  - id: read
    uses: read_stations
  - id: grid
    uses: north_reference
    inputs: {stations: read.stations}
    with: {target: grid, convergence: 1.25}
  - id: trajectory
    uses: minimum_curvature
    inputs: {stations: grid.stations}
    with: {vs_azimuth: 30.0}
    persist: [trajectory]
  - id: uncertainty
    uses: position_uncertainty
    inputs: {trajectory: trajectory.trajectory}
    with: {confidence: 0.9}
    persist: [trajectory]
  - id: dls_check
    uses: check
    inputs: {table: trajectory.trajectory}
    with: {check: dls_limit, params: {limit: 2.0}}
    persist: [results]
  - id: witsml
    uses: write
    inputs: {table: uncertainty.trajectory}
    with: {writer: witsml, filename: trajectory.xml}
  - id: las
    uses: write
    inputs: {table: uncertainty.trajectory}
    with: {writer: las, filename: trajectory.las}
  - id: csv
    uses: write
    inputs: {table: uncertainty.trajectory}
    with: {writer: csv, filename: trajectory.csv}
  - id: summary
    uses: export
    inputs: {trajectory: uncertainty.trajectory, stations: grid.stations, qc: dls_check.results}
    with: {writer: json_summary, filename: summary.json}
  - id: streams
    uses: export
    inputs: {trajectory: uncertainty.trajectory, stations: grid.stations, qc: dls_check.results}
    with: {writer: mcap, filename: processed.mcap}
"""
"""The bundled J-well converted to grid north (γ = 1.25°), integrated with a 30° section
plane, with GYRO-NS uncertainty at 90 % and every export."""

WELL = WellMetadata(
    uwi="05-123-45678",
    wellbore="J-12 ST1",
    service_company="Gyro Services",
    depth_reference="RKB",
    declination=17.0,
)
"""Header fields the sample lacks, given as ``--well`` overrides."""


def run_yaml(
    text: str,
    inputs: dict[str, Path],
    out_dir: Path,
    well: WellMetadata | None = None,
    name: str = "pipeline.yaml",
) -> RunResult:
    """Run the pipeline ``text`` (written to ``out_dir.parent/name``) through the runner."""
    path = out_dir.parent / name
    path.write_text(textwrap.dedent(text).lstrip("\n"))
    registry = load_registry()
    plan = build_plan(load_spec(path), registry)
    return run_plan(plan, registry, inputs=inputs, out_dir=out_dir, well=well)


def without_reports(name: str, directory: Path) -> Path:
    """A copy of the ready pipeline ``pipelines/<name>.yaml`` without its report stages
    (rendering is the report tests' business and costs seconds)."""
    spec = yaml.safe_load((ROOT / "pipelines" / f"{name}.yaml").read_text())
    spec["stages"] = [s for s in spec["stages"] if not s["uses"].endswith("report")]
    path = directory / f"{name}.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path
