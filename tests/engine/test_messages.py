"""Command-line mistakes get one formatted line that says what to do (no pydantic dump, no
URL), with a suggestion where a name is misspelt."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from tests_support import ROOT, gyropipe

SURVEY = ROOT / "pipelines" / "survey.yaml"
SAMPLE = ROOT / "examples" / "stations-j-well.csv"


def run(tmp_path: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    args = ["run", str(SURVEY), "--input", str(SAMPLE), "--out", str(tmp_path / "o"), *extra]
    return subprocess.run(
        [*gyropipe(), *args], capture_output=True, text=True, cwd=ROOT, timeout=120
    )


@pytest.mark.parametrize(
    ("items", "expected"),
    [
        (["latitude=161"], "error: --well latitude=161: input should be less than or equal to 90"),
        (
            ["lattitude=61"],
            "error: --well lattitude=61: unknown field 'lattitude'; did you mean 'latitude'",
        ),
        (
            ["north_reference=tru"],
            "error: --well north_reference=tru: input should be 'true', 'grid' or 'magnetic'",
        ),
    ],
)
def test_well_overrides(tmp_path: Path, items: list[str], expected: str) -> None:
    result = run(tmp_path, *(arg for item in items for arg in ("--well", item)))
    assert result.returncode == 2
    assert result.stderr.startswith(expected), result.stderr
    assert "pydantic" not in result.stderr and "https://" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
