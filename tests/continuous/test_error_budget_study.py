"""The error-budget study (benchmarks/study_error_budget.py) runs end to end on a short plan."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import yaml

from tests_support import ROOT

STUDY = ROOT / "benchmarks" / "study_error_budget.py"
PLAN = ROOT / "examples" / "plans" / "west-siberia-700m.yaml"
FIGURES = ("azimuth", "horizontal", "td-scatter", "breakdown")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def short_plan(tmp_path: Path) -> Path:
    """The study's plan, logged from its start stop (135 m) to 215 m with short stops."""
    plan = yaml.safe_load(PLAN.read_text(encoding="utf-8"))
    plan["survey"]["end_md"] = 215.0
    plan["survey"]["stop"] = {"dwell": 8.0, "move_time": 1.0}
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump(plan), encoding="utf-8")
    return path


def table_row(doc: str, title: str, label: str) -> list[str]:
    """Cells of the row starting with ``label`` in the table after the bold ``title``."""
    section = doc[doc.index(f"**{title}**") :]
    for line in section.splitlines():
        if line.startswith(f"| {label}"):
            return [cell.strip() for cell in line.strip("|").split("|")]
    raise AssertionError(f"no row {label!r} under {title!r}")


def test_study_runs_the_public_pipeline_and_writes_figures_and_numbers(tmp_path: Path) -> None:
    out = tmp_path / "docs"
    doc = out / "error-budget.md"
    out.mkdir()
    doc.write_text(
        "# Kept\n\nprose\n\n<!-- BEGIN numbers: written by benchmarks/study_error_budget.py -->\nold\n<!-- END numbers -->\n\ntail\n",
        encoding="utf-8",
    )
    plan = short_plan(tmp_path)
    args = ["--runs", "1", "--breakdown-runs", "1", "--plan", str(plan), "--out", str(out)]
    done = subprocess.run(
        [sys.executable, str(STUDY), *args, "--work", str(tmp_path / "work")],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    for name in FIGURES:
        data = (out / "figures" / f"error-budget-{name}.png").read_bytes()
        assert data.startswith(PNG_SIGNATURE) and 5_000 < len(data) < 300_000
    text = doc.read_text(encoding="utf-8")
    assert text.startswith("# Kept\n\nprose\n") and text.endswith("\n\ntail\n")
    assert "\nold\n" not in text and "Runs: 1 (seed 1)" in text
    # 80 m of logging: the TD stop's azimuth error is within a few of its predicted σ (≈ 3° for
    # this MEMS tool at 8 s per position); the position error from the tie-in is decimetres
    azi = table_row(text, "Azimuth error", "TD")
    assert 0.0 < float(azi[4]) < 10.0 and abs(float(azi[1])) < 4.0 * float(azi[4])
    horizontal = table_row(text, "Horizontal position error", "TD")
    assert 0.0 < float(horizontal[1]) < 4.0 * float(horizontal[4]) < 4.0
    assert table_row(text, "Azimuth error", "200")[0] == "200"
    assert "| 300 " not in text  # depths past the short plan's TD are not reported
    breakdown = table_row(text, "Breakdown", "gyro bias")
    assert float(breakdown[2]) < 0.1  # a constant gyro bias is removed by the 5-position stops
