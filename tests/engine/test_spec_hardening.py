"""Hardening of pipeline loading (fuzz findings): wrong-typed fields anywhere are located
problems, never a traceback."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

import pytest
import yaml

from hostile_inputs import yaml_binary_aliases
from pipeline.errors import InputFileError, Problem, SpecError
from pipeline.graph import build_plan
from pipeline.io.csv.options import load_profile
from pipeline.sim.spec import load_simulation
from pipeline.spec import load_spec
from pipeline.yamlsource import MAX_NODES, MAX_SCALAR_CHARS
from tests_support import gyropipe_cli

WRONG: list[Any] = [[], ["x"], {}, {"a": [1]}, 1, 2.5, None, True, [[1]], [{"a": 1}]]
"""Values of the wrong type for some field: lists, mappings, numbers, null."""

BASE: dict[str, Any] = {
    "name": "demo",
    "version": "1",
    "inputs": {"stations": {}},
    "well": {"latitude": 50.0},
    "defaults": {"with": {"vs_azimuth": 10.0}, "persist_format": "csv"},
    "stages": [
        {"id": "read", "uses": "read_stations", "with": {"input": "stations"}},
        {
            "id": "traj",
            "uses": "minimum_curvature",
            "description": "integrate",
            "inputs": {"stations": "read.stations"},
            "with": {"vs_azimuth": 45.0},
            "persist": ["trajectory"],
        },
    ],
}
FIELDS: list[tuple[str | int, ...]] = [
    ("name",),
    ("version",),
    ("inputs",),
    ("inputs", "stations"),
    ("well",),
    ("well", "latitude"),
    ("defaults",),
    ("defaults", "with"),
    ("defaults", "persist_format"),
    ("stages",),
    ("stages", 0),
    *(("stages", 1, key) for key in ("id", "uses", "description", "inputs", "with", "persist")),
    ("stages", 1, "inputs", "stations"),
    ("stages", 1, "with", "vs_azimuth"),
    ("stages", 1, "persist", 0),
    ("stages", 0, "with", "input"),
]


def test_a_list_as_stage_id_is_a_located_problem_not_a_traceback(tmp_path: Path):
    """6 of 1,000 mutated pipelines ended in ``TypeError: unhashable type: 'list'``."""
    path = tmp_path / "p.yaml"
    path.write_text(
        "name: p\nversion: 1\ninputs: {stations: {}}\n"
        "stages: [{id: [], uses: read_stations, with: {input: stations}}]\n"
    )
    for extra in ([], ["--set", "read.x=1"]):
        result = gyropipe_cli("validate", str(path), *extra)
        assert result.returncode == 2, result.stderr
        assert f"{path}:4:15: stages.0.id: Input should be a valid string" in result.stderr
        assert "Traceback" not in result.stderr


@pytest.mark.parametrize("field", FIELDS, ids=lambda f: ".".join(map(str, f)))
def test_wrong_types_anywhere_are_located_problems(tmp_path: Path, registry, field):
    for wrong in WRONG:
        data = yaml.safe_load(yaml.safe_dump(BASE))
        target = data
        for key in field[:-1]:
            target = target[key]
        target[field[-1]] = wrong
        path = tmp_path / "p.yaml"
        path.write_text(yaml.safe_dump(data))
        for overrides in ([], ["traj.vs_azimuth=1"], ["read.input=[1]"]):
            try:
                build_plan(load_spec(path, overrides), registry)
            except SpecError as exc:
                for problem in exc.problems:
                    assert problem.location.line or problem.location.file.startswith("--set"), (
                        wrong,
                        problem,
                    )


# ------------------------------------------------------------------ alias bombs, nesting


def laughs(levels: int = 9, width: int = 9, key: str = "stages") -> str:
    """A "billion laughs" document: each level an anchored list of ``width`` aliases of
    the level below; ``key`` takes the top level (line ``levels + 4``, column
    ``len(key) + 3``)."""
    lines = ["name: p", "version: 1", "a0: &a0 [" + ", ".join(["x"] * width) + "]"]
    for i in range(1, levels + 1):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * width) + "]")
    lines.append(f"{key}: *a{levels}")
    return "\n".join(lines) + "\n"


def refused_at_once(path: Path) -> Problem:
    """The one problem ``load_spec`` finds in ``path``, within a second."""
    start = time.perf_counter()
    with pytest.raises(SpecError) as info:
        load_spec(path)
    assert time.perf_counter() - start < 1.0
    (problem,) = info.value.problems
    return problem


def test_alias_bomb_is_refused_at_once(tmp_path: Path):
    """Nine levels of nine aliases grew ``validate`` to 387 MB and past 60 s."""
    path = tmp_path / "laughs.yaml"
    path.write_text(laughs())
    problem = refused_at_once(path)
    assert str(problem.location) == f"{path}:13:9"
    assert "aliases expand the document to" in problem.message
    assert f"more than {MAX_NODES:,}" in problem.message


@pytest.mark.parametrize("command", ["validate", "run"])
def test_alias_bomb_is_refused_by_the_cli(tmp_path: Path, command: str):
    path = tmp_path / "laughs.yaml"
    path.write_text(laughs())
    extra = ["--input", f"s={path}", "--out", str(tmp_path / "out")] if command == "run" else []
    result = gyropipe_cli(command, str(path), *extra)
    assert result.returncode == 2, result.stderr
    assert f"{path}:13:9: aliases expand the document" in result.stderr


def test_alias_bomb_in_a_simulation_plan_and_a_csv_profile(tmp_path: Path):
    plan = tmp_path / "plan.yaml"
    plan.write_text(laughs(key="survey"))
    start = time.perf_counter()
    with pytest.raises(SpecError, match=r"plan.yaml:13:9: aliases expand"):
        load_simulation(plan)
    assert time.perf_counter() - start < 1.0
    result = gyropipe_cli("simulate", str(plan), "--out", str(tmp_path / "sim"))
    assert result.returncode == 2 and f"{plan}:13:9: aliases expand" in result.stderr
    profile = tmp_path / "profile.yaml"
    profile.write_text(laughs(key="aliases").replace("name: p\nversion: 1\n", ""))
    with pytest.raises(InputFileError, match=r"profile.yaml:11:10: aliases expand"):
        load_profile(profile)


def test_aliases_of_a_large_scalar_are_limited_by_their_expanded_size(tmp_path: Path):
    """Issue 32 item 9: a 1 MB ``!!binary`` anchor aliased 20,000 times built ~20 GB of
    bytes (MemoryError): the node count stayed small. The expanded text is counted too."""
    path = tmp_path / "binary.yaml"
    path.write_bytes(yaml_binary_aliases(100_000, 200))  # 75 kB of bytes per copy
    problem = refused_at_once(path)
    assert str(problem.location) == f"{path}:4:8"
    assert problem.message == (
        f"aliases expand the document to 20,100,021 characters of scalars (keys included), more than "
        f"{MAX_SCALAR_CHARS:,}: refused (this alias alone expands to 100,000 characters)"
    )


@pytest.mark.parametrize("command", ["set", "option"])
def test_a_bad_timestamp_in_set_and_option_is_one_line(tmp_path: Path, command: str):
    """Issue 32 item 13: ``!!timestamp abc`` ended in AttributeError ('groupdict')."""
    path = tmp_path / "p.yaml"
    path.write_text(
        "name: p\nversion: 1\ninputs: {s: {}}\n"
        "stages: [{id: read, uses: read_stations, with: {input: s}}]\n"
    )
    if command == "set":
        result = gyropipe_cli("validate", str(path), "--set", "read.options=!!timestamp abc")
        where = "--set read.options=!!timestamp abc: value"
    else:
        src = tmp_path / "s.csv"
        src.write_text("md,inc,azi\n0,0,0\n100,1,10\n")
        out = str(tmp_path / "o.csv")
        result = gyropipe_cli("convert", str(src), "--out", out, "--option", "x=!!timestamp abc")
        where = "--option x=!!timestamp abc"
    assert result.returncode == 2, result.stderr
    assert f"{where}: 'abc' is not a valid YAML timestamp: expected a date" in result.stderr
    assert "Traceback" not in result.stderr


def test_a_moderate_alias_is_fine_and_located_at_its_anchor(tmp_path: Path, registry):
    path = tmp_path / "p.yaml"
    path.write_text(
        "name: p\nversion: 1\ninputs: {s: {}}\nstages:\n"
        "  - id: read\n    uses: read_stations\n    with: &w {input: s}\n"
        "  - id: again\n    uses: read_stations\n    with: *w\n"
    )
    plan = build_plan(load_spec(path), registry)
    assert [s.id for s in plan.stages] == ["read", "again"]


@pytest.mark.parametrize(
    ("text", "where", "message"),
    [
        ("stages: &a [*a]\n", "3:13", "alias inside the node it refers to"),
        ("stages: &a {x: [*a]}\n", "3:17", "alias inside the node it refers to"),
        ("stages: " + "[" * 500 + "]" * 500 + "\n", "3:108", "nested deeper than 100 levels"),
        (
            "".join(f"a{i}: &a{i} [*a{i - 1}]\n" if i else "a0: &a0 [x]\n" for i in range(120))
            + "stages: *a119\n",
            "",
            "nested deeper than 100 levels",
        ),
    ],
    ids=["self-alias", "alias-in-mapping", "deep-brackets", "deep-alias-chain"],
)
def test_recursive_and_deep_documents_are_located_problems(
    tmp_path: Path, text: str, where: str, message: str
):
    """These ended in RecursionError tracebacks."""
    path = tmp_path / "p.yaml"
    path.write_text("name: p\nversion: 1\n" + text)
    result = gyropipe_cli("validate", str(path))
    assert result.returncode == 2, result.stderr
    assert message in result.stderr and f"{path}:{where}" in result.stderr
    assert "Traceback" not in result.stderr


def test_set_values_have_the_same_limits(tmp_path: Path, registry):
    path = tmp_path / "p.yaml"
    path.write_text(
        "name: p\nversion: 1\ninputs: {s: {}}\n"
        "stages: [{id: read, uses: read_stations, with: {input: s}}]\n"
    )
    bomb = "{" + laughs(5).replace("\n", ", ").replace("stages: ", "z: ").rstrip(", ") + "}"
    bomb = bomb.replace("name: p, version: 1, ", "")
    with pytest.raises(SpecError) as info:
        build_plan(load_spec(path, [f"read.options={bomb}", "read.options=[1"]), registry)
    found = [str(p) for p in info.value.problems]
    assert found[0].startswith("--set read.options={a0") and ": value: aliases expand" in found[0]
    assert "value: column 3: malformed YAML: the '[' at column 1 is not closed" in found[1]


# ------------------------------------------------------------------ every problem at once


ALL_AT_ONCE = """\
name: not a name
inputs: {stations: {}}
stages:
  - id: read
    uses: read_stations
  - id: traj
    uses: minimum_curvatur
    inputs: {stations: read}
  - id: out
    uses: write
  - id: read
    uses: write
    inputs: {table: read}
    with: {writer: nope, filename: ../x.csv}
  - id: broken
    uses: [write]
  - id: after
    uses: write
    inputs: {table: broken}
    with: {writer: csv, colour: red}
"""


def test_validate_reports_every_problem_in_one_pass(tmp_path: Path):
    """`validate` used to stop at the first shape error (a missing `version`), and never
    checked the params of a stage whose id is a duplicate."""
    path = tmp_path / "p.yaml"
    path.write_text(ALL_AT_ONCE)
    result = gyropipe_cli("validate", str(path))
    assert result.returncode == 2, result.stderr
    found = [line.strip() for line in result.stderr.splitlines()[1:]]
    expected = [
        "1:7: name: String should match pattern",  # shape problems first
        "16:11: stages.4.uses: Input should be a valid string",
        "7:11: unknown stage 'minimum_curvatur'; did you mean 'minimum_curvature'?",
        "11:9: duplicate stage id 'read'",
        "9:5: stage 'out' (write): missing required field 'writer'",  # not wired, no params
        "9:5: stage 'out' (write): input port 'table' is not wired",
        "14:20: stage 'read' (write): writer: Value error, no writer named 'nope'",
        "14:36: stage 'read' (write): filename: Value error, a path",
        "20:25: stage 'after' (write): unknown field 'colour'",
    ]
    assert len(found) == len(expected), result.stderr
    for line, start in zip(found, expected, strict=True):
        assert line.startswith(f"{path}:{start}"), (line, start)
    # the input wired to the stage of invalid shape is not reported again
    assert "no stage with id 'broken'" not in result.stderr


def test_version_is_optional(tmp_path: Path, registry):
    path = tmp_path / "p.yaml"
    path.write_text(
        "name: p\ninputs: {s: {}}\nstages: [{id: read, uses: read_stations, with: {input: s}}]\n"
    )
    plan = build_plan(load_spec(path), registry)
    assert plan.spec.version == "1"
    path.write_text(path.read_text().replace("name: p\n", "name: p\nversion: 2.5\n"))
    assert build_plan(load_spec(path), registry).spec.version == "2.5"


def test_invalid_inputs_block_does_not_make_every_read_stage_a_problem(tmp_path: Path, registry):
    path = tmp_path / "p.yaml"
    path.write_text(
        "name: p\ninputs: [s]\nstages: [{id: read, uses: read_stations, with: {input: s}}]\n"
    )
    with pytest.raises(SpecError) as info:
        build_plan(load_spec(path), registry)
    assert [str(p) for p in info.value.problems] == [
        f"{path}:2:9: inputs: Input should be a valid dictionary"
    ]


def test_a_control_character_is_located(tmp_path: Path):
    """PyYAML's reader error carries no mark: it was reported without a line."""
    path = tmp_path / "p.yaml"
    path.write_text("name: p\nstages:\n  - id: b\x01c\n")
    with pytest.raises(SpecError) as info:
        load_spec(path)
    assert [str(p) for p in info.value.problems] == [
        f"{path}:3:10: malformed YAML: character U+0001 is not allowed "
        "(special characters are not allowed)"
    ]


# ------------------------------------------------------- scalars no safe constructor builds


@pytest.mark.parametrize(
    ("line", "column", "message"),
    [
        (
            "    with: {<<: *v, vs_azimuth: 1}",
            12,
            "YAML merge keys ('<<') are not supported: write the keys out",
        ),
        ("    description: !!python/name:os.system", 18, "YAML tag 'tag:yaml.org,2002:python"),
        ("    description: !custom x", 18, "YAML tag '!custom' is not allowed"),
        ("    description: !!int abc", 18, "'abc' is not a valid YAML int: invalid literal"),
        ("    description: 2026-13-45", 18, "'2026-13-45' is not a valid YAML timestamp"),
        ("    description: !!bool maybe", 18, "'maybe' is not a valid YAML bool: 'maybe'"),
        ("    description: !!timestamp abc", 18, "'abc' is not a valid YAML timestamp: expected"),
    ],
    ids=["merge-key", "python-tag", "custom-tag", "bad-int", "bad-date", "bad-bool", "bad-stamp"],
)
def test_a_scalar_yaml_cannot_build_is_a_located_problem(
    tmp_path: Path, registry, line: str, column: int, message: str
):
    """Fuzz findings: these were ConstructorError/ValueError tracebacks out of the YAML
    loader (a merge key ``<<``, a tag on a scalar, a tagged or date-like value of the wrong
    form), in pipelines, simulation plans and CSV profiles alike."""
    path = tmp_path / "p.yaml"
    path.write_text(
        "name: p\nversion: 1\nwell: {latitude: &v 50.0}\ninputs: {s: {}}\nstages:\n"
        "  - id: read\n    uses: read_stations\n    with: {input: s}\n"
        f"  - id: traj\n    uses: minimum_curvature\n    inputs: {{stations: read.stations}}\n"
        f"{line}\n"
    )
    with pytest.raises(SpecError) as info:
        build_plan(load_spec(path), registry)
    found = [str(p) for p in info.value.problems]
    assert found[0].startswith(f"{path}:12:{column}: {message}"), found


def test_a_bad_date_and_a_merge_key_in_a_simulation_plan_are_located(tmp_path: Path):
    path = tmp_path / "plan.yaml"
    path.write_text(
        "name: p\nsite: {latitude: 61.0, longitude: 73.0, date: 2026-13-45}\n"
        "well: {sections: [{kind: vertical, length: 10}]}\ntool: &t {preset: ideal}\n"
        "survey: {<<: *t, mode: point, every: 5}\n"
    )
    with pytest.raises(SpecError) as info:
        load_simulation(path)
    found = [str(p) for p in info.value.problems]
    assert f"{path}:2:47: '2026-13-45' is not a valid YAML timestamp" in found[0]
    assert any(p.startswith(f"{path}:5:10: YAML merge keys") for p in found), found


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize(
    ("command", "what"),
    [("validate", "pipeline"), ("run", "pipeline"), ("simulate", "plan"), ("budget", "plan")],
)
def test_a_fifo_as_pipeline_or_plan_is_refused_without_blocking(
    tmp_path: Path, command: str, what: str
):
    """Adversarial pass: ``gyropipe validate fifo.yaml`` (and run, simulate, budget) blocked
    for good on the FIFO's read, waiting for a writer."""
    path = tmp_path / "fifo.yaml"
    os.mkfifo(path)
    extra = {
        "run": ["--input", f"s={path}", "--out", str(tmp_path / "out")],
        "simulate": ["--out", str(tmp_path / "out")],
    }.get(command, [])
    result = gyropipe_cli(command, str(path), *extra)
    assert result.returncode == 2, result.stderr
    assert f"{path}: cannot read {what}: " in result.stderr
    assert "not a regular file (a FIFO)" in result.stderr
