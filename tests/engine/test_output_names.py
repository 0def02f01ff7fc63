"""Output file names are checked when the pipeline is validated (fuzz finding: a ``write``
with ``filename: ../../escape.csv`` passed ``validate`` and failed inside the run)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from pipeline.errors import SpecError
from pipeline.filenames import MAX_LENGTH, check_output_filename
from pipeline.graph import build_plan
from pipeline.spec import load_spec
from tests_support import ROOT, gyropipe_cli

BAD = ["../../escape.csv", "/tmp/abs.csv", "sub/../../x.csv", "run.json", "", "..", "a\\b.csv"]
STAGES = [  # pipeline, stage id: every built-in stage that writes a named file
    ("survey.yaml", "export_csv"),  # write
    ("survey.yaml", "export_summary"),  # export
    ("survey.yaml", "report"),  # report
    ("calibration.yaml", "report"),  # calibration_report
]


def with_filename(pipeline: str, stage_id: str, names: list[str], out: Path) -> Path:
    """``pipeline`` with the stage's filename set to each of ``names`` in turn, one copy of
    the stage per name (ids ``<stage_id>_<i>``)."""
    data = yaml.safe_load((ROOT / "pipelines" / pipeline).read_text())
    stages = data["stages"]
    (stage,) = [s for s in stages if s["id"] == stage_id]
    stages.remove(stage)
    for i, name in enumerate(names):
        stages.append(
            {**stage, "id": f"{stage_id}_{i}", "with": {**stage.get("with", {}), "filename": name}}
        )
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


def filename_lines(path: Path) -> list[int]:
    return [n for n, line in enumerate(path.read_text().splitlines(), 1) if "filename:" in line]


@pytest.mark.parametrize(("pipeline", "stage_id"), STAGES)
def test_bad_output_names_are_located_at_validate_time(
    tmp_path: Path, registry, pipeline: str, stage_id: str
):
    path = with_filename(pipeline, stage_id, BAD, tmp_path / "p.yaml")
    with pytest.raises(SpecError) as info:
        build_plan(load_spec(path), registry)
    found = {p.location.line: p.message for p in info.value.problems}
    bad_lines = filename_lines(path)[-len(BAD) :]
    for line, name in zip(bad_lines, BAD, strict=True):
        assert line in found, (name, [str(p) for p in info.value.problems])
        assert f"stage '{stage_id}_" in found[line] and "filename:" in found[line]


def test_cli_validate_refuses_escaping_names_with_their_location(tmp_path: Path):
    path = with_filename("survey.yaml", "export_csv", BAD[:3], tmp_path / "p.yaml")
    result = gyropipe_cli("validate", str(path))
    assert result.returncode == 2, result.stderr
    for line in filename_lines(path)[-3:]:
        assert f"{path}:{line}:" in result.stderr
    assert "a path, not a file name" in result.stderr


@pytest.mark.parametrize("name", ["trajectory.csv", "a", "Survey_1.final-v2.las", "x" * MAX_LENGTH])
def test_plain_names_are_accepted(name: str):
    assert check_output_filename(name) == name


@pytest.mark.parametrize(
    ("name", "why"),
    [
        ("", "must not be empty"),
        ("../x", "a path"),
        ("/abs", "a path"),
        ("C:\\x", "a path"),
        ("..", "not a file name"),
        ("run.json", "manifest"),
        (".hidden", "not a plain file name"),
        ("a b", "not a plain file name"),
        ("x" * (MAX_LENGTH + 1), f"at most {MAX_LENGTH}"),
    ],
)
def test_refused_names_say_why(name: str, why: str):
    with pytest.raises(ValueError, match=why):
        check_output_filename(name)


DUPLICATES = """\
name: dup
inputs: {stations: {}}
stages:
  - id: read
    uses: read_stations
    with: {input: stations}
  - id: traj
    uses: minimum_curvature
    inputs: {stations: read.stations}
    persist: true
  - id: out
    uses: write
    inputs: {table: traj.trajectory}
    with: {writer: csv}
  - id: again
    uses: write
    inputs: {table: traj.trajectory}
    with:
      writer: csv
      filename: OUT.csv
  - id: p
    uses: write
    inputs: {table: traj.trajectory}
    with: {writer: parquet, filename: traj.trajectory.parquet}
  - id: out_report
    uses: report
    inputs: {trajectory: traj.trajectory}
  - id: page
    uses: write
    inputs: {table: traj.trajectory}
    with: {writer: csv, filename: out_report.pdf}
"""


def test_two_stages_writing_one_file_are_refused_at_validate_time(tmp_path: Path):
    """Two stages writing one file name — a default ('out.csv' of stage 'out'), equal up to
    case, a persisted table's, a report's — failed only at run time, in the second stage."""
    path = tmp_path / "dup.yaml"
    path.write_text(DUPLICATES)
    result = gyropipe_cli("validate", str(path))
    assert result.returncode == 2, result.stderr
    assert result.stderr.splitlines()[1:] == [
        f"  {path}:20:17: stage 'again' writes 'OUT.csv', as stage 'out' does ('out.csv' up to "
        f"case) ({path}:11:9): give one of them another filename",
        f"  {path}:24:39: stage 'p' writes 'traj.trajectory.parquet', as stage 'traj' does "
        f"({path}:7:9): give one of them another filename",
        f"  {path}:31:35: stage 'page' writes 'out_report.pdf', as stage 'out_report' does "
        f"({path}:25:9): give one of them another filename",
    ]


GIVEN = {"clearance.yaml": ["clearance.reference_hole_diameter=0.3112"]}
"""What a bundled pipeline leaves to its user (no example value in a shipped pipeline)."""


def test_every_bundled_pipeline_writes_distinct_files(registry):
    for path in sorted((ROOT / "pipelines").glob("*.yaml")):
        build_plan(load_spec(path, GIVEN.get(path.name, [])), registry)
