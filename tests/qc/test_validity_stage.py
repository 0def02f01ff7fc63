"""Validity checks inside a pipeline: a clean survey passes, a biased gyro is caught and
named, the station still reaches compassing unless its policy drops it."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pyarrow.parquet as pq

from tests_support import ROOT, gyropipe_cli, simulate_and_run

PLAN = """
name: qc-run
seed: 5
site: {{latitude: 61.25, longitude: 73.4, date: 2026-11-21,
        magnetic: {{total_field: 59731.0, dip: 78.29, declination: 17.0}}}}
well:
  sections:
    - {{kind: vertical, length: 30}}
    - {{kind: build, dls: 9.0, inc: 45, azi: 120}}
tool: {{preset: nav-grade, overrides: {overrides}}}
survey: {{mode: point, every: 30, dwell: 20, move_time: 2}}
"""


def run(tmp_path: Path, overrides: str) -> Path:
    return simulate_and_run(tmp_path, PLAN.format(overrides=overrides))


def test_clean_survey_passes(tmp_path: Path):
    out = run(tmp_path, "{}")
    summary = pq.read_table(out / "validity.summary.parquet")
    assert set(summary.column("status").to_pylist()) == {"ok"}
    qc = pq.read_table(out / "validity.qc.parquet")
    checks = set(qc.column("check").to_pylist())
    assert {"earth_rate", "gravity", "latitude", "rate_along_gravity"} <= checks
    references = json.loads(qc.schema.metadata[b"gyropipe.references"])
    assert "Li and Götze (2001)" in references["gravity"]
    assert "7.292115e-05" in references["earth_rate"]


def test_biased_gyro_is_caught_and_named(tmp_path: Path):
    out = run(tmp_path, "{gyro: {bias: [0.0, 3.0, 0.0]}}")
    summary = pq.read_table(out / "validity.summary.parquet").to_pylist()
    flagged = [row for row in summary if row["status"] != "ok"]
    assert len(flagged) >= len(summary) - 1
    named = [row for row in flagged if row["suspect"].startswith("gyro y")]
    assert len(named) >= 0.9 * len(flagged), [row["diagnosis"] for row in flagged]
    stations = pq.read_table(out / "compass.stations.parquet")
    assert stations.num_rows == len(summary)  # flag policy: stations are kept, marked


def test_a_magnetometer_bias_is_named_on_the_terminal_in_the_summary_and_the_report(
    tmp_path: Path,
):
    """An 800 nT bias on magnetometer x of an otherwise ideal tool: the CLI prints the suspect
    and the estimate, the summary names it, the report's QC section shows the diagnosis."""
    plan = PLAN.replace("preset: nav-grade", "preset: ideal")
    (tmp_path / "plan.yaml").write_text(
        plan.format(
            overrides="{gyro: {noise_density: 0.003}, accelerometer: {noise_density: 0.01}, "
            "magnetometer: {bias: [800.0, 0.0, 0.0], noise_density: 2.0}}"
        )
    )
    sim = tmp_path / "sim"
    gyropipe_cli("simulate", str(tmp_path / "plan.yaml"), "--out", str(sim), check=True)
    out = tmp_path / "out"
    pipeline = str(ROOT / "pipelines" / "point-gyro.yaml")
    result = gyropipe_cli(
        "run", pipeline, "--input", str(sim / "samples.parquet"), "--out", str(out)
    )
    assert result.returncode == 0, result.stderr
    printed = re.search(
        r"suspect mag x at (\d+) stations: mag x: bias ≈ \+(\d+\.\d) ± ", result.stdout
    )
    assert printed, result.stdout
    summary = pq.read_table(out / "validity.summary.parquet").to_pylist()
    failed = [row for row in summary if "magnetic" in row["failed_checks"]]
    assert int(printed.group(1)) == len(failed) >= 3
    assert {row["suspect"] for row in failed} == {"mag x"}
    assert abs(float(printed.group(2)) - 800.0) < 5.0
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "Diagnosis of failed validity checks" in html and "mag x: bias ≈ +" in html
