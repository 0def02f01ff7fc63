"""The LAS fast path's two rewrites (fixed-width blocks, packed ragged blocks) and the
careful path, driven through ``gp.read`` and ``gyropipe convert``: the same values either
way, and a bad cell (out of the float range, or missing) reported at its file line whichever
rewrite declined it (a log keeps a text cell as text: no error there)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pytest
from click.testing import CliRunner

import pipeline as gp
from pipeline.cli import main
from pipeline.errors import InputFileError
from pipeline.io.las import fast as las_fast
from pipeline.io.las import rows as las_rows

HEAD = (
    "~Version\n VERS. 2.0 : v\n WRAP. NO : w\n~Well\n NULL. -999.25 : null\n"
    "~Curve\n DEPT.M : depth\n A.M : a\n B.M : b\n~A\n"
)
FIRST = HEAD.count("\n") + 1
"""File line of the first data row."""
VALUES = [(100.0 + i, i / 8, -3.5 * i) for i in range(12)]
FIXED = [f"{d:10.2f} {a:12.4f} {b:12.4f}" for d, a, b in VALUES]
RAGGED = [
    f"{d!r} {a!r}\t{b!r}" if i % 2 else f" {d!r}  {a!r} {b!r}  "
    for i, (d, a, b) in enumerate(VALUES)
]


@pytest.fixture
def paths(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Which rewrite or path read each block: 'fixed', 'packed', 'careful'."""
    taken: list[str] = []
    fixed, packed, careful = las_fast._fixed_width, las_fast._packed, las_rows._slow_cells

    def spy_fixed(*args: object, **kwargs: object) -> object:
        layout = fixed(*args, **kwargs)  # type: ignore[arg-type]
        taken.extend(["fixed"] if layout is not None else [])
        return layout

    def spy_packed(*args: object, **kwargs: object) -> object:
        taken.append("packed")
        return packed(*args, **kwargs)  # type: ignore[arg-type]

    def spy_careful(*args: object, **kwargs: object) -> object:
        taken.append("careful")
        return careful(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(las_fast, "_fixed_width", spy_fixed)
    monkeypatch.setattr(las_fast, "_packed", spy_packed)
    monkeypatch.setattr(las_rows, "_slow_cells", spy_careful)
    return taken


def _write(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "log.las"
    path.write_text(HEAD + "\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize(("lines", "path_taken"), [(FIXED, "fixed"), (RAGGED, "packed")])
def test_each_layout_reads_every_value_by_its_path(
    tmp_path: Path, paths: list[str], lines: list[str], path_taken: str
) -> None:
    frame = gp.read(_write(tmp_path, lines), kind="log")
    assert set(paths) == {path_taken}
    assert frame["DEPT"].tolist() == [v[0] for v in VALUES]
    assert frame["A"].tolist() == [v[1] for v in VALUES]
    assert frame["B"].tolist() == [v[2] for v in VALUES]
    assert frame["source_line"].tolist() == list(range(FIRST, FIRST + len(VALUES)))


@pytest.mark.parametrize("lines", [FIXED, RAGGED], ids=["fixed-width", "ragged"])
@pytest.mark.parametrize("bad", ["1e999", ""], ids=["out of range", "missing"])
def test_a_bad_cell_is_reported_at_its_line_by_gp_read_and_the_cli(
    tmp_path: Path, paths: list[str], lines: list[str], bad: str
) -> None:
    row, first_try = 7, "fixed" if lines is FIXED else "packed"
    cells = lines[row].split()
    lines = [
        *lines[:row],
        lines[row].replace(cells[1], f"{bad:>{len(cells[1])}}"),
        *lines[row + 1 :],
    ]
    path = _write(tmp_path, lines)
    with pytest.raises(InputFileError) as info:
        gp.read(path, kind="log")
    assert info.value.line == FIRST + row
    assert paths[0] == first_try and paths[-1] == "careful"  # declined, then located
    result = CliRunner().invoke(main, ["convert", str(path), str(tmp_path / "out.parquet")])
    assert result.exit_code != 0
    assert re.search(rf"log\.las:{FIRST + row}\b", result.output), result.output


def test_a_comma_in_a_value_is_refused_as_the_careful_path_refuses_it(
    tmp_path: Path, paths: list[str]
) -> None:
    """``2.0,3.0`` is one cell (LAS 2 splits at blanks): a value too few, at its line; the
    fast path does not take the comma for a delimiter."""
    lines = ["1.0 2.0 3.0", "2.0,3.0 4.0", "3.0 4.0 5.0"]
    with pytest.raises(InputFileError, match="expected 3 values") as info:
        gp.read(_write(tmp_path, lines), kind="log")
    assert info.value.line == FIRST + 1
    assert paths == ["careful"]


def test_a_changed_layout_of_the_same_width_is_found_again(
    tmp_path: Path, paths: list[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Blocks whose columns move but keep the line width: the first block's layout fails
    the second (no check, a value too few), whose own layout is then found; all fixed."""
    monkeypatch.setattr(las_fast, "BLOCK", 200)
    moved = [f"{d:8.2f} {a:14.4f} {b:12.4f}" for d, a, b in VALUES]
    assert {len(line) for line in moved} == {len(FIXED[0])}
    frame = gp.read(_write(tmp_path, FIXED[:6] + moved[6:]), kind="log")
    assert set(paths) == {"fixed"}
    assert frame["A"].tolist() == [v[1] for v in VALUES]
    assert frame["B"].tolist() == [v[2] for v in VALUES]


def test_pyarrow_csv_trims_the_padding_around_a_float() -> None:
    """What the fixed-width rewrite relies on in the pyarrow installed: spaces and tabs
    around a value are trimmed by the float64 conversion, a blank cell is no number."""
    options = pacsv.ConvertOptions(
        column_types={"a": pa.float64(), "b": pa.float64()},
        null_values=[],
        strings_can_be_null=False,
    )
    read = pacsv.ReadOptions(column_names=["a", "b"])
    table = pacsv.read_csv(
        pa.BufferReader(b"   1.5,\t -2.25 \n  3e2 , 4\n"), read, convert_options=options
    )
    assert table.column("a").to_pylist() == [1.5, 300.0]
    assert table.column("b").to_pylist() == [-2.25, 4.0]
    with pytest.raises(pa.ArrowInvalid):
        pacsv.read_csv(pa.BufferReader(b"1.5,   \n"), read, convert_options=options)
    assert np.float64(pa.__version__.split(".")[0]) >= 14  # the version these ran on: 26
