"""``validate`` checks what ``run`` would fail on (issue 32 item 14): a parameter that is
not a finite number (``1e400`` is inf to pydantic, ``.nan``) and a port persisted twice are
problems at their YAML location, before any stage runs."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests_support import ROOT, gyropipe_cli

SURVEY = ROOT / "pipelines" / "survey.yaml"
VS_AZIMUTH = "vs_azimuth: 0.0"
PERSIST = "persist: [trajectory]"


def _pipeline(tmp_path: Path, old: str, new: str) -> Path:
    text = SURVEY.read_text()
    assert old in text
    path = tmp_path / "survey.yaml"
    path.write_text(text.replace(old, new))
    return path


def _line_of(path: Path, text: str) -> int:
    return next(i for i, line in enumerate(path.read_text().splitlines(), 1) if text in line)


@pytest.mark.parametrize(
    ("value", "shown"), [("1e400", "inf"), ("-1e999", "-inf"), (".nan", "nan")]
)
def test_a_parameter_that_is_not_finite_is_refused_at_its_line(
    tmp_path: Path, value: str, shown: str
) -> None:
    """Before: validate said ok; run printed NumPy warnings and a 4-line pydantic error."""
    path = _pipeline(tmp_path, VS_AZIMUTH, f"vs_azimuth: {value}")
    result = gyropipe_cli("validate", path)
    assert result.returncode == 2
    line = _line_of(path, "vs_azimuth:")
    assert result.stderr.splitlines()[1:] == [
        f"  {path}:{line}:19: stage 'trajectory' (minimum_curvature): vs_azimuth is {shown}: "
        "expected a finite number"
    ]


def test_a_non_finite_parameter_given_by_set_is_refused_naming_the_option() -> None:
    result = gyropipe_cli("validate", SURVEY, "--set", "trajectory.vs_azimuth=1e400")
    assert result.returncode == 2
    assert result.stderr.splitlines()[1:] == [
        "  --set trajectory.vs_azimuth=1e400: stage 'trajectory' (minimum_curvature): "
        "vs_azimuth is inf: expected a finite number"
    ]


def test_a_port_persisted_twice_is_refused_at_the_second(tmp_path: Path) -> None:
    """Before: validate said ok and run failed after every stage had run."""
    path = _pipeline(tmp_path, PERSIST, "persist: [trajectory, trajectory]")
    result = gyropipe_cli("validate", path)
    assert result.returncode == 2
    line = _line_of(path, "persist: [trajectory, trajectory]")
    assert result.stderr.splitlines()[1:] == [
        f"  {path}:{line}:27: stage 'trajectory' persists 'trajectory' twice: name each output once"
    ]
