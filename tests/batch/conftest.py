"""Fixtures of the batch tests (helpers are in batch_support)."""

from __future__ import annotations

from pathlib import Path

import pytest
from batch_support import survey_pipeline


@pytest.fixture
def survey(tmp_path: Path) -> Path:
    """The survey test pipeline, written into ``tmp_path``."""
    return survey_pipeline(tmp_path)
