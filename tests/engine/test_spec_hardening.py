"""Hardening of pipeline loading (fuzz findings): wrong-typed fields anywhere are located
problems, never a traceback."""

from __future__ import annotations

import subprocess
from pathlib import Path
from typing import Any

import pytest
import yaml

from pipeline.errors import SpecError
from pipeline.graph import build_plan
from pipeline.spec import load_spec
from tests_support import gyropipe

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
        result = subprocess.run(
            [*gyropipe(), "validate", str(path), *extra], capture_output=True, text=True
        )
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
