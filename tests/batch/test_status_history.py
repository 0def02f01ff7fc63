"""``gyropipe status DIR`` and ``gyropipe history WELL`` read the ledger back; a run that
consumes a drift calibration records which one (file hash, instruments, selected
estimates) and the drift correction it applied (instrument, estimate, rate and σ); a run
that corrects none records none."""

from __future__ import annotations

import contextlib
import hashlib
import json
import sqlite3
from pathlib import Path

import pyarrow.parquet as pq
from batch_support import (
    ROOT,
    change_one_azimuth,
    corrupt,
    make_wells,
    runs,
)

from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.runner import run_plan
from pipeline.spec import load_spec
from tests_support import gyropipe_cli


def test_status_and_history_report_what_the_ledger_holds(tmp_path: Path, survey: Path):
    paths = make_wells(tmp_path / "in", ["S1", "S2", "S3"])
    corrupt(paths[2])
    out = tmp_path / "out"
    pattern = tmp_path / "in" / "*.csv"
    assert gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out).returncode == 1
    change_one_azimuth(paths[0])
    assert (
        gyropipe_cli(
            "batch", survey, "--inputs", pattern, "--out", out, "--only-changed"
        ).returncode
        == 1
    )

    status = gyropipe_cli("status", out)
    assert status.returncode == 0, status.output
    lines = status.stdout.splitlines()
    assert lines[0] == f"ledger {out / 'ledger.sqlite'}: 3 wells — 2 done, 1 failed"
    assert lines[1].split()[:3] == ["batch", "1", "finished"]
    assert lines[1].endswith(": 2 done, 1 failed")
    assert lines[2].endswith(": 1 done, 1 failed, 1 skipped")
    by_well = {line.split()[0]: line for line in lines[4:]}
    assert by_well["S1"].split()[1] == "done" and by_well["S1"].endswith("input changed: stations")
    assert by_well["S3"].split()[1] == "failed" and "  read: S3.csv:" in by_well["S3"]
    assert "InputFileError" not in status.stdout and str(tmp_path) not in by_well["S3"]

    document = json.loads(gyropipe_cli("status", out, "--json").stdout)
    assert [b["status"] for b in document["batches"]] == ["finished", "finished"]
    assert {w["well"]: w["status"] for w in document["wells"]} == {
        "S1": "done",
        "S2": "done",
        "S3": "failed",
    }
    # a survey corrects no drift: none recorded (a failed run's: not recorded)
    assert {w["well"]: w["drift"] for w in document["wells"]} == {"S1": [], "S2": [], "S3": None}
    latest = {r["well"]: r["drift"] for r in runs(out / "ledger.sqlite")}  # (rows by id)
    assert latest == {"S1": "[]", "S2": "[]", "S3": None}
    assert "drift" not in status.stdout

    history = gyropipe_cli("history", "S1", "--dir", out)
    assert history.returncode == 0, history.output
    text = history.stdout
    assert text.startswith("well S1: 2 run(s)\nrun 1 (batch 1) done")
    assert "run 4 (batch 2) done" in text
    assert "  why: new well" in text and "  why: input changed: stations" in text
    digest = hashlib.sha256(paths[0].read_bytes()).hexdigest()
    assert f"  input stations: {paths[0]} sha256 {digest[:16]}…" in text
    assert f"  outputs: {out / 'S1'} (3 files)" in text
    document = json.loads(gyropipe_cli("history", "S1", "--dir", out, "--json").stdout)
    assert [r["inputs"]["stations"]["sha256"] for r in document["runs"]][-1] == digest

    assert gyropipe_cli("history", "nope", "--dir", out).returncode == 2
    assert gyropipe_cli("status", tmp_path / "elsewhere").returncode == 2
    assert "drift" not in text


def test_a_ledger_of_an_earlier_version_gains_the_drift_column(tmp_path: Path, survey: Path):
    """A ledger an earlier version made has no column drift: opening it adds the column,
    null for the runs it holds — not recorded, never read as no correction applied — and
    the next run records its own."""
    (path,) = make_wells(tmp_path / "in", ["S1"])
    out = tmp_path / "out"
    ledger = out / "ledger.sqlite"
    command = ("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out)
    assert gyropipe_cli(*command).returncode == 0
    with contextlib.closing(sqlite3.connect(ledger)) as db:
        db.execute("ALTER TABLE runs DROP COLUMN drift")  # the runs table as it was made
        assert "drift" not in {row[1] for row in db.execute("PRAGMA table_info(runs)")}

    history = gyropipe_cli("history", "S1", "--dir", out)
    assert history.returncode == 0, history.output
    assert "  drift applied: not recorded (run by an earlier version, or recovered)\n" in (
        history.stdout
    )
    assert [r["drift"] for r in runs(ledger)] == [None]
    change_one_azimuth(path)
    assert gyropipe_cli(*command, "--only-changed").returncode == 0
    assert [r["drift"] for r in runs(ledger)] == [None, "[]"]


FREE_GYRO_CALIBRATED = """\
name: free-gyro-calibrated
version: "1.0"
inputs:
  readings: {description: free-gyro readings}
  calibration: {description: a calibrate_drift result}
well:
  north_reference: "true"
stages:
  - id: read
    uses: read_free_gyro
  - id: calibration
    uses: read_calibration_result
  - id: drift
    uses: correct_drift
    inputs: {readings: read.free_gyro, calibration: calibration.calibration_result}
    with: {source: calibration}
    persist: [stations]
"""


def test_the_calibration_a_run_consumed_is_recorded(tmp_path: Path):
    registry = load_registry()
    calibration = run_plan(
        build_plan(load_spec(ROOT / "pipelines" / "calibration.yaml"), registry),
        registry,
        inputs={"calibration": ROOT / "examples" / "calibration-ig50.csv"},
        out_dir=tmp_path / "cal",
    )
    result_file = calibration.out_dir / "drift.result.parquet"
    assert (
        gyropipe_cli(
            "simulate",
            ROOT / "examples" / "plans" / "j-well-free-gyro.yaml",
            "--out",
            tmp_path / "sim",
        ).returncode
        == 0
    )
    pipeline = tmp_path / "free-gyro-calibrated.yaml"
    pipeline.write_text(FREE_GYRO_CALIBRATED)
    manifest = tmp_path / "wells.csv"
    manifest.write_text(
        "well_id,readings,calibration,tool_serial\n"
        f"FG-1,{tmp_path / 'sim' / 'readings.parquet'},{result_file},IG50-0417\n"
    )
    out = tmp_path / "out"
    batch = gyropipe_cli("batch", pipeline, "--manifest", manifest, "--out", out, "--workers", "1")
    assert batch.returncode == 0, batch.output

    (run,) = runs(out / "ledger.sqlite")
    (recorded,) = json.loads(run["calibration"])
    table = pq.read_table(result_file).to_pylist()
    (chosen,) = [r for r in table if r["selected"]]
    assert recorded == {  # which tool's estimate was applied is the drift column's
        "stage": "calibration",
        "input": "calibration",
        "sha256": hashlib.sha256(result_file.read_bytes()).hexdigest(),
        "instruments": ["IG50-0417"],
        "selected": [{k: chosen[k] for k in ("instrument", "method", "drift_deg_h")}],
    }
    (applied,) = json.loads(run["drift"])  # the manifest's serial picked the one instrument
    assert (applied["instrument"], applied["source"], applied["method"]) == (
        "IG50-0417",
        "calibration",
        chosen["method"],
    )
    assert (applied["rate_deg_h"], applied["sigma_deg_h"]) == (
        chosen["drift_deg_h"],
        chosen["sigma_deg_h"],
    )  # the same doubles
    text = gyropipe_cli("history", "FG-1", "--dir", out).stdout
    assert (
        f"calibration (calibration, input calibration sha256 {recorded['sha256'][:16]}…): "
        f"selected IG50-0417 fit {chosen['drift_deg_h']:.4f} deg/h" in text
    )
    assert (
        f"  drift applied (drift.readings): {chosen['drift_deg_h']:.4f} ± "
        f"{chosen['sigma_deg_h']:.4f} deg/h, calibration of IG50-0417 (fit, " in text
    )
