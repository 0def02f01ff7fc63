"""Fixtures of the export tests, and the fuzz tests' directory."""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from export_support import EXPORTS, SAMPLE, WELL, run_yaml

from pipeline.runner import RunResult


@pytest.fixture(scope="session")
def exports_run(tmp_path_factory: pytest.TempPathFactory) -> RunResult:
    """One run of :data:`export_support.EXPORTS` on the bundled sample, shared by the export
    tests (each reads its outputs only)."""
    return run_yaml(EXPORTS, {"stations": SAMPLE}, tmp_path_factory.mktemp("exports") / "out", WELL)


@pytest.fixture(scope="session")
def trajectory(exports_run: RunResult) -> pa.Table:
    """The exports run's trajectory with its uncertainty columns, as persisted."""
    return pq.read_table(exports_run.out_dir / "uncertainty.trajectory.parquet")


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A directory for a test module's fuzzed input files."""
    return tmp_path_factory.mktemp("fuzz")
