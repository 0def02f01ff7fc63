"""What a batch worker reports of a well after its run: the drift calibrations it consumed
and the drift corrections it applied, found without reading the run's streamed outputs
whole (the series and the raw samples of a continuous well stay streams: a worker holds one
well's batches at a time, issue #20)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml
from batch_support import STATIONS, survey_pipeline

from pipeline.batch.publish import staging_dir
from pipeline.batch.worker import WellTask, _calibration, _drift, run_well
from pipeline.executing import PipelineRef
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.runner import run_plan
from pipeline.spec import load_spec
from pipeline.streams import TableStream
from tests_support import ROOT, gyropipe_cli, without_report


def test_calibrations_are_found_without_reading_streamed_outputs(tmp_path: Path):
    plan_file = tmp_path / "plan.yaml"
    plan = yaml.safe_load((ROOT / "examples" / "plans" / "j-well-continuous.yaml").read_text())
    plan["survey"].update(start_md=600, end_md=640)
    plan_file.write_text(yaml.safe_dump(plan))
    gyropipe_cli("simulate", str(plan_file), "--out", "sim", cwd=tmp_path, check=True)
    pipeline = without_report("continuous-gyro", tmp_path)
    registry = load_registry()
    built = build_plan(load_spec(pipeline), registry)
    result = run_plan(
        built,
        registry,
        inputs={"samples": tmp_path / "sim" / "samples.parquet"},
        out_dir=tmp_path / "out",
    )
    ports = result.tables._ports
    streamed = sorted(k for k, v in ports.items() if isinstance(v, TableStream))
    assert ("continuous", "series") in streamed  # the run did stream

    assert _calibration(built, result) == []  # this pipeline consumes no calibration
    assert _drift(built, result) == []  # and corrects no free-gyro drift

    assert sorted(k for k, v in ports.items() if isinstance(v, TableStream)) == streamed


def test_a_well_is_on_disk_before_it_is_published_and_written_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """docs/batch.md: a well's outputs appear in OUT/<well> only complete — every file in
    the staging directory fsynced (its final contents: nothing written after), the staging
    directory itself fsynced, then renamed, then OUT fsynced; and the run is published once
    (no second directory of the run renamed on the way)."""
    survey = survey_pipeline(tmp_path)
    spec = load_spec(survey).spec
    assert spec is not None
    ref = PipelineRef(str(survey), spec)
    events: list[tuple[str, str]] = []
    real_fsync, real_rename = os.fsync, os.rename

    def fsync(fd: int) -> None:
        events.append(("fsync", os.readlink(f"/proc/self/fd/{fd}")))
        real_fsync(fd)

    def rename(src: str | Path, dst: str | Path) -> None:
        events.append(("rename", f"{src} -> {dst}"))
        real_rename(src, dst)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(os, "rename", rename)
    out = tmp_path / "out"
    task = WellTask("W", 1, 1, ref.digest, {"stations": str(STATIONS)}, {}, str(out), "{}")
    outcome = run_well(task, ref)
    assert outcome.status == "done", outcome.error
    staging = staging_dir(out, "W", 1)
    renames = [e for e in events if e[0] == "rename"]
    assert renames == [("rename", f"{staging} -> {out / 'W'}")]
    published = events.index(renames[0])
    synced = [path for kind, path in events[:published] if kind == "fsync"]
    files = sorted(p.name for p in (out / "W").iterdir())
    assert "run.json" in files and "batch.json" in files and "trajectory.csv" in files
    assert sorted(Path(p).name for p in synced if Path(p).parent == staging) == files
    assert synced[-1] == str(staging)  # the directory's entries, after every file
    assert str(out) in [path for kind, path in events[published:] if kind == "fsync"]
