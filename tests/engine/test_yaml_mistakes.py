"""Indentation mistakes in a pipeline file, and malformed ``--set`` values, are told in
gyropipe's words (issue 28 item 13): one line, ``file:line:column``, what is out of line
against what (a mapping's keys, a list's ``-`` items) — not PyYAML's parser text such as
``expected <block end>, but found '<block mapping start>'``."""

from __future__ import annotations

from pathlib import Path

import pytest

import pipeline as gp
from pipeline.errors import SpecError
from tests_support import ROOT, gyropipe_cli

SURVEY = (ROOT / "pipelines" / "survey.yaml").read_text()
STATIONS = ROOT / "examples" / "stations-j-well.csv"

MISTAKES = {
    # a key one space too many: read.with under read.uses
    "key too deep": (
        ("    uses: read_stations\n    with:", "    uses: read_stations\n     with:"),
        "indented 1 space more than the key 'uses' (line {uses}, column 5): "
        "a mapping's keys must line up",
    ),
    "key too shallow": (
        ("    uses: read_stations\n    with:", "    uses: read_stations\n   with:"),
        "indented 1 space less than the key 'uses' (line {uses}, column 5): "
        "a mapping's keys must line up",
    ),
    "list item out of line": (
        ("\n  - id: trajectory", "\n   - id: trajectory"),
        "indented 1 space more than the list's items (line {read}, column 3): "
        "a list's '-' items must line up",
    ),
    "tab": (
        ("\n  - id: trajectory", "\n\t- id: trajectory"),
        "a tab; YAML indents with spaces only",
    ),
}


def _broken(tmp_path: Path, name: str) -> tuple[Path, int, int, str]:
    """The shipped survey pipeline with mistake ``name``: its path, the (1-based) line and
    column of the mistake and the expected message."""
    (old, new), message = MISTAKES[name]
    assert SURVEY.count(old) == 1
    text = SURVEY.replace(old, new)
    lines = text.splitlines()
    changed = next(
        i for i, (a, b) in enumerate(zip(lines, SURVEY.splitlines(), strict=True)) if a != b
    )
    column = len(lines[changed]) - len(lines[changed].lstrip(" ")) + 1
    numbers = {
        "uses": next(i for i, line in enumerate(lines, 1) if "uses: read_stations" in line),
        "read": next(i for i, line in enumerate(lines, 1) if line == "  - id: read"),
    }
    path = tmp_path / "survey.yaml"
    path.write_text(text)
    return path, changed + 1, column, "malformed YAML: " + message.format(**numbers)


@pytest.mark.parametrize("name", list(MISTAKES))
def test_validate_locates_the_indentation_mistake(tmp_path: Path, name: str):
    path, line, column, message = _broken(tmp_path, name)
    result = gyropipe_cli("validate", path)
    assert result.returncode == 2, result.stderr
    assert f"{path}:{line}:{column}: {message}" in result.stderr
    for parser in ("<block", "expected <", "while parsing", "cannot start any token"):
        assert parser not in result.stderr
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize("name", ["key too shallow", "list item out of line"])
def test_run_and_the_api_say_the_same(tmp_path: Path, name: str):
    path, line, column, message = _broken(tmp_path, name)
    result = gyropipe_cli("run", path, "--input", STATIONS, "--out", tmp_path / "out")
    assert result.returncode == 2 and f"{path}:{line}:{column}: {message}" in result.stderr
    with pytest.raises(SpecError) as raised:
        gp.run(path, STATIONS)
    assert [str(p) for p in raised.value.problems] == [f"{path}:{line}:{column}: {message}"]


@pytest.mark.parametrize(
    ("value", "said"),
    [
        ("{md_unit: ft", "column 13: malformed YAML: the '{' at column 1 is not closed"),
        ("[1, 2", "column 6: malformed YAML: the '[' at column 1 is not closed"),
        ("a: b: c", "column 5: malformed YAML: ': ' inside a value; put the value in quotes"),
    ],
)
def test_a_set_value_names_its_column(value: str, said: str):
    result = gyropipe_cli("validate", "pipelines/survey.yaml", "--set", f"read.options={value}")
    assert result.returncode == 2
    assert f"--set read.options={value}: value: {said}" in result.stderr
    assert "<stream end>" not in result.stderr and "Traceback" not in result.stderr
