"""``gyropipe status DIR`` and ``gyropipe history WELL`` read the ledger back; a run that
consumes a drift calibration records which one (file hash, instrument, estimate)."""

from __future__ import annotations

import hashlib
import json
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
    selected = [r for r in table if r["selected"]]
    assert recorded == {
        "stage": "calibration",
        "input": "calibration",
        "sha256": hashlib.sha256(result_file.read_bytes()).hexdigest(),
        "instruments": ["IG50-0417"],
        "selected": [{k: r[k] for k in ("instrument", "method", "drift_deg_h")} for r in selected],
        "tool_serial": "IG50-0417",
    }
    text = gyropipe_cli("history", "FG-1", "--dir", out).stdout
    assert (
        f"calibration (calibration, input calibration sha256 {recorded['sha256'][:16]}…): tool IG50-0417; IG50-0417 fit"
        in text
    )
