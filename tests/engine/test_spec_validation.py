"""Pipeline spec validation: every problem is reported, together, at its YAML line:column."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import pyarrow as pa
import pytest

from pipeline.errors import SpecError
from pipeline.graph import build_plan
from pipeline.registry import Registry, StageContext, StageDef
from pipeline.spec import load_spec
from pipeline.tables import AnyTable, Stations, Trajectory
from tests_support import gyropipe_cli

HEAD = """
name: demo
version: 1
inputs:
  stations: {}
stages:
"""


def problems(path: Path, registry: Registry, overrides: list[str] | None = None) -> list[str]:
    """Validation problems as 'line:column: message' strings ([] when valid)."""
    with pytest.raises(SpecError) as info:
        build_plan(load_spec(path, overrides), registry)
    out = []
    for p in info.value.problems:
        assert p.location.file in (str(path), *(f"--set {o}" for o in overrides or []))
        out.append(f"{p.location.line}:{p.location.column}: {p.message}")
    return out


def passthrough(
    inputs: Mapping[str, pa.Table], params: object, ctx: StageContext
) -> dict[str, pa.Table]:
    return {"left": inputs["table"], "right": inputs["table"]}


def test_valid_pipeline_orders_stages_by_dependency(write_yaml, registry):
    path = write_yaml(
        HEAD
        + """
  - id: out
    uses: write
    inputs: {table: traj.trajectory}
    with: {writer: parquet}
  - id: traj
    uses: minimum_curvature
    inputs: {stations: read}
  - id: read
    uses: read_stations
"""
    )
    plan = build_plan(load_spec(path), registry)
    assert [s.id for s in plan.stages] == ["read", "traj", "out"]
    assert plan.stages[1].wiring == {"stations": ("read", "stations")}
    assert plan.spec.version == "1"


def test_malformed_yaml_points_at_the_syntax_error(write_yaml, registry):
    path = write_yaml("name: demo\nstages:\n  - id: a\n    uses: [x\n")
    (msg,) = problems(path, registry)
    assert msg.startswith("5:1: malformed YAML")


def test_empty_and_non_mapping_files(write_yaml, registry):
    assert problems(write_yaml("", "a.yaml"), registry) == ["1:1: empty file"]
    (msg,) = problems(write_yaml("- a\n- b\n", "b.yaml"), registry)
    assert msg.startswith("1:1: a pipeline must be a mapping")


def test_missing_and_unknown_top_level_fields(write_yaml, registry):
    path = write_yaml("name: demo\nstagez: []\n")
    found = problems(path, registry)
    assert found == [
        "1:1: missing required field 'stages'",
        "2:1: unknown field 'stagez'; did you mean 'stages'?",
    ]


def test_duplicate_yaml_key(write_yaml, registry):
    path = write_yaml(HEAD + "  - id: a\n    uses: read_stations\n    uses: write\n")
    assert problems(path, registry) == ["8:5: duplicate key 'uses'"]


def test_python_tags_are_refused(write_yaml, registry):
    path = write_yaml(
        HEAD + "  - id: a\n    uses: !!python/object/apply:os.system ['echo hacked']\n"
    )
    (msg,) = problems(path, registry)
    assert msg.startswith("7:11:")
    assert "python/object/apply:os.system" in msg


def test_unknown_stage_suggests_close_names(write_yaml, registry):
    path = write_yaml(HEAD + "  - id: a\n    uses: minimum_curvatur\n")
    (msg,) = problems(path, registry)
    assert msg.startswith(
        "7:11: unknown stage 'minimum_curvatur'; did you mean 'minimum_curvature'"
    )
    assert "registered:" in msg


def test_unknown_and_mistyped_params(write_yaml, registry):
    path = write_yaml(
        HEAD
        + """
  - id: read
    uses: read_stations
  - id: traj
    uses: minimum_curvature
    inputs: {stations: read}
    with:
      vs_azimut: 10
      tie_north: north
"""
    )
    found = problems(path, registry)
    assert any(
        m.startswith("13:7: stage 'traj' (minimum_curvature): unknown field 'vs_azimut'")
        for m in found
    ), found
    assert any(
        m.startswith("14:18: stage 'traj' (minimum_curvature): tie_north:") and "'north'" in m
        for m in found
    ), found
    assert len(found) == 2


def test_missing_required_param_and_unregistered_writer(write_yaml, registry):
    path = write_yaml(
        HEAD
        + """
  - id: read
    uses: read_stations
  - id: out1
    uses: write
    inputs: {table: read}
  - id: out2
    uses: write
    inputs: {table: read}
    with: {writer: xlsx}
"""
    )
    found = problems(path, registry)
    assert found[0] == "9:5: stage 'out1' (write): missing required field 'writer'"
    assert found[1].startswith(
        "15:20: stage 'out2' (write): writer: Value error, no writer named 'xlsx'"
    )


def test_pipeline_input_must_be_declared(write_yaml, registry):
    path = write_yaml(HEAD + "  - id: read\n    uses: read_stations\n    with: {input: survey}\n")
    (msg,) = problems(path, registry)
    assert msg.startswith("8:19: stage 'read': input 'survey' is not a pipeline input")


def test_wiring_problems(write_yaml, registry):
    path = write_yaml(
        HEAD
        + """
  - id: read
    uses: read_stations
  - id: a
    uses: minimum_curvature
    inputs: {stations: nowhere.x}
  - id: b
    uses: minimum_curvature
    inputs: {stations: read.table}
  - id: c
    uses: minimum_curvature
    inputs: {stations: read, extra: read}
  - id: d
    uses: minimum_curvature
"""
    )
    found = problems(path, registry)
    assert found == [
        "11:24: input 'stations': no stage with id 'nowhere'",
        "14:24: input 'stations': stage 'read' has no output port 'table' (outputs: stations)",
        "17:30: stage 'c' (minimum_curvature) has no input port 'extra' (ports: stations)",
        "18:5: stage 'd' (minimum_curvature): input port 'stations' is not wired",
    ]


def test_ambiguous_input(write_yaml, registry, add_stage):
    add_stage(
        StageDef(
            "tests.split",
            passthrough,
            "two outputs",
            inputs={"table": AnyTable},
            outputs={"left": AnyTable, "right": AnyTable},
        )
    )
    path = write_yaml(
        HEAD
        + """
  - id: read
    uses: read_stations
  - id: split
    uses: tests.split
    inputs: {table: read}
  - id: out
    uses: write
    inputs: {table: split}
    with: {writer: parquet}
"""
    )
    (msg,) = problems(path, registry)
    assert msg.startswith(
        "14:21: input 'table': 'split' is ambiguous, stage 'split' has outputs left, right"
    )


def test_contract_mismatch_between_ports(write_yaml, registry, add_stage):
    add_stage(
        StageDef(
            "tests.wants_trajectory",
            passthrough,
            "needs tvd",
            inputs={"table": Trajectory},
            outputs={"left": AnyTable, "right": AnyTable},
        )
    )
    path = write_yaml(
        HEAD
        + """
  - id: read
    uses: read_stations
  - id: t
    uses: tests.wants_trajectory
    inputs: {table: read.stations}
"""
    )
    (msg,) = problems(path, registry)
    assert msg.startswith(
        "11:21: input 'table' from read.stations: Stations does not satisfy Trajectory"
    )
    assert "column 'tvd' missing" in msg
    assert issubclass(Trajectory, Stations)  # the reverse direction is accepted


def test_duplicate_ids_and_persist_of_unknown_port(write_yaml, registry):
    path = write_yaml(
        HEAD
        + """
  - id: read
    uses: read_stations
    persist: [stations, nope]
  - id: read
    uses: read_stations
"""
    )
    assert problems(path, registry) == [
        "10:9: duplicate stage id 'read'",
        "9:25: stage 'read' has no output port 'nope' to persist (outputs: stations)",
    ]


def test_cycle_is_reported_with_its_path(write_yaml, registry, add_stage):
    add_stage(
        StageDef(
            "tests.loop",
            passthrough,
            "loop",
            inputs={"table": AnyTable},
            outputs={"left": AnyTable, "right": AnyTable},
        )
    )
    path = write_yaml(
        HEAD
        + """
  - id: a
    uses: tests.loop
    inputs: {table: c.left}
  - id: b
    uses: tests.loop
    inputs: {table: a.left}
  - id: c
    uses: tests.loop
    inputs: {table: b.right}
"""
    )
    (msg,) = problems(path, registry)
    assert msg == "9:13: cycle between stages: a → b → c → a"


def test_all_problems_are_reported_together(write_yaml, registry):
    path = write_yaml(
        HEAD
        + """
  - id: read
    uses: read_stationz
  - id: traj
    uses: minimum_curvature
    inputs: {stations: read}
    with: {vs_azimuth: [1, 2]}
  - id: traj
    uses: write
"""
    )
    found = problems(path, registry)
    assert len(found) == 5
    assert found[0].startswith("8:11: unknown stage 'read_stationz'")
    assert found[1].startswith("13:9: duplicate stage id 'traj'")
    assert found[2].startswith("12:24: stage 'traj' (minimum_curvature): vs_azimuth:")
    # the stage whose id is a duplicate is checked too
    assert found[3] == "13:5: stage 'traj' (write): missing required field 'writer'"
    assert found[4] == "13:5: stage 'traj' (write): input port 'table' is not wired"


def test_set_overrides(write_yaml, registry):
    path = write_yaml(
        HEAD
        + """
  - id: read
    uses: read_stations
  - id: traj
    uses: minimum_curvature
    inputs: {stations: read}
"""
    )
    plan = build_plan(load_spec(path, ["traj.vs_azimuth=45", "traj.tie_tvd=12.5"]), registry)
    params = plan.stages[1].params
    assert (params.vs_azimuth, params.tie_tvd) == (45.0, 12.5)  # type: ignore[attr-defined]
    assert plan.digest != build_plan(load_spec(path), registry).digest

    bad = ["nostage.x=1", "traj=1", "traj.vs_azimuth=north"]
    found = problems(path, registry, bad)
    assert found[0].startswith("0:0: no stage with id 'nostage'")
    assert found[1] == "0:0: expected STAGE.PARAM=VALUE"
    assert found[2].startswith("0:0: stage 'traj' (minimum_curvature): vs_azimuth:")


def test_cli_validate_reports_locations_and_exit_code(write_yaml, tmp_path: Path):
    path = write_yaml(HEAD + "  - id: a\n    uses: nope\n")
    result = gyropipe_cli("validate", str(path))
    assert result.returncode == 2
    assert f"{path}:7:11: unknown stage 'nope'" in result.output
    ok = gyropipe_cli("validate", "pipelines/survey.yaml")
    assert ok.returncode == 0, ok.output
    assert "ok: pipeline 'survey'" in ok.output
