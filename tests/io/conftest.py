"""Fixtures of the export tests."""

from __future__ import annotations

import pytest
from export_support import EXPORTS, SAMPLE, WELL, run_yaml

from pipeline.runner import RunResult


@pytest.fixture(scope="session")
def exports_run(tmp_path_factory: pytest.TempPathFactory) -> RunResult:
    """One run of :data:`export_support.EXPORTS` on the bundled sample, shared by the export
    tests (each reads its outputs only)."""
    return run_yaml(EXPORTS, {"stations": SAMPLE}, tmp_path_factory.mktemp("exports") / "out", WELL)
