"""A survey program's CSV export puts its units on the line under the column names
(``MD,Inc,Azi`` over ``(ft),(°),(°)`` or ``ft,deg,deg``), or rules the header off with
dashes: that line is the header's, its units are the columns', and a unit there that the
header cell contradicts, or that is no unit of its column, is refused at that line."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest
from vendor_exports import survey_pipeline

import pipeline as gp
from pipeline.errors import InputFileError
from tests_support import gyropipe_cli

TITLE = "Well: ACME 7H\nNorth Reference: Grid\n\n"
ROWS = "0.00,0.00,0.00\n1000.00,0.00,0.00\n1100.00,3.00,127.50\n1200.00,6.00,127.50\n"
"""Data rows of every listing here (ft, deg, grid north)."""


def listing(tmp_path: Path, header: str, under: str | None, name: str = "listing.csv") -> Path:
    path = tmp_path / name
    path.write_text(TITLE + header + "\n" + (under + "\n" if under is not None else "") + ROWS)
    return path


@pytest.mark.parametrize(
    "under", ["(ft),(°),(°)", "ft,deg,deg", "[ft],[deg],[dega]", " FT , Degrees , deg "]
)
def test_a_units_row_gives_the_columns_their_units(tmp_path: Path, under: str):
    stated = gp.read(listing(tmp_path, "MD (ft),Inc (deg),Azi (deg)", None), kind="stations")
    table = gp.read(listing(tmp_path, "MD,Inc,Azi", under, "units-row.csv"), kind="stations")
    assert table["md"].tolist() == pytest.approx([0.0, 304.8, 335.28, 365.76], abs=1e-9)
    assert table[["md", "inc", "azi"]].equals(stated[["md", "inc", "azi"]])
    assert table["source_line"].tolist() == [6, 7, 8, 9]  # the data begin under the units
    assert table.attrs["north_reference"] == "grid"


def test_a_rule_under_the_header_is_passed_over(tmp_path: Path):
    path = listing(tmp_path, "MD (m),Inc (deg),Azi (deg)", "--------,---------,=========")
    table = gp.read(path, kind="stations")
    assert table["md"].tolist() == [0.0, 1000.0, 1100.0, 1200.0]
    assert table["source_line"].tolist()[0] == 6


def test_a_units_row_the_header_contradicts_is_refused_at_its_line(tmp_path: Path):
    path = listing(tmp_path, "MD (ft),Inc,Azi", "m,deg,deg")
    with pytest.raises(InputFileError) as caught:
        gp.read(path, kind="stations")
    assert str(caught.value).startswith(f"{path}:5 (column 'MD (ft)'): the header says 'ft'")
    assert "the units row under it 'm'" in str(caught.value)


def test_a_unit_that_is_not_its_column_s_is_refused_at_its_line(tmp_path: Path):
    path = listing(tmp_path, "MD,Inc,Azi", "ft,deg,ft")
    with pytest.raises(InputFileError) as caught:
        gp.read(path, kind="stations")
    assert str(caught.value).startswith(f"{path}:5 (column 'Azi'): units row: unit 'ft' is")
    assert "expected an angle" in str(caught.value)


def test_the_pipeline_reads_the_units_row_as_the_header_would(tmp_path: Path):
    """The same listing, units under the names or in them, gives the same trajectory."""
    pipeline = survey_pipeline(tmp_path)
    outs = []
    for header, under in (("MD (ft),Inc (deg),Azi (deg)", None), ("MD,Inc,Azi", "ft,deg,deg")):
        stations = listing(tmp_path, header, under, f"{len(outs)}.csv")
        out = tmp_path / f"out{len(outs)}"
        gyropipe_cli("run", pipeline, "--input", f"stations={stations}", "--out", out, check=True)
        with (out / "trajectory.csv").open() as fh:
            outs.append([row for row in csv.reader(fh) if row and not row[0].startswith("#")])
    assert outs[0] == outs[1]
    assert [row[0] for row in outs[1][1:]] == ["0", "304.8", "335.28", "365.76"]
