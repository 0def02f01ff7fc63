"""What a batch worker reports of a well after its run: the drift calibrations it consumed,
found without reading the run's streamed outputs whole (the series and the raw samples of a
continuous well stay streams: a worker holds one well's batches at a time, issue #20)."""

from __future__ import annotations

from pathlib import Path

import yaml

from pipeline.batch.worker import _calibration
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

    assert sorted(k for k, v in ports.items() if isinstance(v, TableStream)) == streamed
