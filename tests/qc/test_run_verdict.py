"""The verdict of a run on the command line and in run.json: the QC line beside "ok", a
failed acceptance gate as its own exit code (3) and ``status: rejected`` with the outputs
published, and a batch that counts rejected wells apart from failed ones (issue 28, item 10)."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pandas as pd

import pipeline as gp
from tests_support import ROOT, gyropipe_cli

STATIONS = ROOT / "examples" / "stations-j-well.csv"
GATES_YAML = """\
name: gates-only
version: "1.0"
inputs:
  inrun: {description: in-run stations}
  outrun: {description: out-run stations}
well:
  north_reference: "true"
stages:
  - {id: read_in, uses: read_stations, with: {input: inrun}}
  - {id: read_out, uses: read_stations, with: {input: outrun}}
  - id: gates
    uses: acceptance_gates
    inputs: {inrun: read_in.stations, outrun: read_out.stations}
    persist: [gates]
"""


def out_run(directory: Path, turn: float) -> Path:
    """The bundled listing with every azimuth turned by ``turn`` degrees (the out-run)."""
    lines = STATIONS.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("MD")) + 1
    rows = []
    for line in lines[start:]:
        md, inc, azi = line.split(",")
        rows.append(f"{md},{inc},{(float(azi) + turn) % 360:.2f}")
    path = directory / f"out-{turn:g}.csv"
    path.write_text("\n".join([*lines[:start], *rows]) + "\n")
    return path


def gates_only(directory: Path) -> Path:
    """The gates-only pipeline, written into ``directory``."""
    (path := directory / "gates.yaml").write_text(GATES_YAML)
    return path


def test_the_run_line_gives_the_qc_verdict(tmp_path: Path) -> None:
    """8-DLS-failures-and-"ok" reproducer: failed checks counted beside ok, exit 0."""
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run",
        ROOT / "pipelines" / "survey.yaml",
        "--input",
        STATIONS,
        "--out",
        out,
        "--set",
        "dls_check.params={limit: 2.0}",
        "--set",
        "report.formats=[html]",
    )
    assert result.returncode == 0, result.output
    trajectory = pd.read_csv(out / "trajectory.csv", comment="#")
    dls = next(c for c in trajectory.columns if c.lower().startswith("dls"))
    over = int((trajectory[dls] > 2.0).sum())
    assert over > 0
    assert result.stdout.splitlines()[-1] == (
        f"ok: {out / 'run.json'} — QC: {over} failed checks (dls_limit: {over}) at {over} stations"
    )
    assert json.loads((out / "run.json").read_text())["status"] == "ok"

    clean = gyropipe_cli(
        "run",
        ROOT / "pipelines" / "survey.yaml",
        "--input",
        STATIONS,
        "--out",
        tmp_path / "clean",
        "--set",
        "report.formats=[html]",
    )
    assert clean.returncode == 0, clean.output
    assert clean.stdout.splitlines()[-1] == (
        f"ok: {tmp_path / 'clean' / 'run.json'} — QC: all {len(trajectory)} checks passed"
    )


def test_a_failed_acceptance_gate_exits_3_and_is_recorded(tmp_path: Path) -> None:
    gates_pipeline = gates_only(tmp_path)
    out = tmp_path / "out"
    bad = out_run(tmp_path, 2.0)  # 2° beyond the 1° azimuth gate
    result = gyropipe_cli(
        "run",
        gates_pipeline,
        "--input",
        f"inrun={STATIONS}",
        "--input",
        f"outrun={bad}",
        "--out",
        out,
    )
    assert result.returncode == 3, result.output
    assert result.stdout.splitlines()[-1] == (
        f"rejected: {out / 'run.json'} — acceptance FAILED (gates.azimuth)"
    )
    manifest = json.loads((out / "run.json").read_text())
    assert manifest["status"] == "rejected" and manifest["acceptance"]["status"] == "fail"
    assert (out / "gates.gates.parquet").is_file()  # the evidence is published

    api = gp.run(gates_pipeline, {"inrun": STATIONS, "outrun": bad})
    assert api.manifest["status"] == "rejected"
    agreeing = gp.run(gates_pipeline, {"inrun": STATIONS, "outrun": out_run(tmp_path, 0.5)})
    assert agreeing.manifest["status"] == "ok"


def test_a_batch_counts_rejected_wells_apart(tmp_path: Path) -> None:
    gates_pipeline = gates_only(tmp_path)
    manifest = tmp_path / "wells.csv"
    good, bad = out_run(tmp_path, 0.5), out_run(tmp_path, 2.0)
    manifest.write_text(f"well_id,inrun,outrun\nA-1,{STATIONS},{good}\nB-1,{STATIONS},{bad}\n")
    out = tmp_path / "batch"
    result = gyropipe_cli(
        "batch", gates_pipeline, "--manifest", manifest, "--out", out, "--workers", "1"
    )
    assert result.returncode == 3, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["counts"] == {
        "done": 1,
        "rejected": 1,
        "failed": 0,
        "skipped": 0,
        "interrupted": 0,
    }
    rows = {w["well"]: w for w in summary["wells"]}
    assert rows["B-1"]["status"] == "rejected"
    assert rows["B-1"]["detail"] == "rejected: acceptance FAILED (gates.azimuth)"
    assert (out / "B-1" / "gates.gates.parquet").is_file()
    with sqlite3.connect(out / "ledger.sqlite") as db:  # the ledger's own vocabulary
        recorded = dict(db.execute("SELECT well, status || ' ' || coalesce(note, '') FROM runs"))
    assert recorded == {"A-1": "done ", "B-1": "done rejected: acceptance FAILED (gates.azimuth)"}
    status = gyropipe_cli("status", out)
    assert status.returncode == 0, status.output
    assert "1 done, 1 rejected" in status.stdout
    assert any(line.split()[:2] == ["B-1", "rejected"] for line in status.stdout.splitlines())
