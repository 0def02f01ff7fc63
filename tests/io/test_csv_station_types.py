"""A vendor's CSV survey listing says what each row is in a text column (``Survey Type``,
``Station Type``, ``Comment``): its tie-in row is the survey's start and read; a row of a
projection (``Projection to TD``, ``PTB``) or an interpolation is no measurement, left out
with a warning at its line naming its MD (reader option ``stations: all`` reads it); the
column is kept as ``station_type``."""

from __future__ import annotations

import warnings
from pathlib import Path

import lasio
import pytest
from vendor_exports import survey_pipeline

import pipeline as gp
from pipeline.errors import InputFileError, InputFileWarning
from tests_support import gyropipe_cli

LISTING = """\
Company: Example Operator
Well: 58/1-A1
Survey Date: 2026-03-02
North Reference: true

MD (m),Inc (deg),Azi (deg),TVD (m),{column}
0.00,0.00,0.00,0.00,{tie}
300.00,0.00,0.00,300.00,{survey}
330.00,1.50,45.00,329.99,{survey}
360.00,3.00,45.00,359.94,{survey}
380.00,4.00,45.00,379.88,{last}
"""
"""Lines 7 to 11: the tie-in, three survey stations and the last row."""


def listing(tmp_path: Path, column: str, tie: str, survey: str, last: str) -> Path:
    path = tmp_path / "listing.csv"
    path.write_text(LISTING.format(column=column, tie=tie, survey=survey, last=last))
    return path


@pytest.mark.parametrize(
    ("column", "tie", "survey", "last"),
    [
        ("Survey Type", "Tie-In", "Gyro NS", "Projection to TD"),
        ("Station Type", "Tie On", "MWD", "Proj. to Bit"),
        ("Comment", "TIE ON", "", "PTB"),
        ("Comments", "Tie point", "", "Interpolated"),
    ],
)
def test_a_projection_row_is_left_out_and_the_tie_in_read(
    tmp_path: Path, column: str, tie: str, survey: str, last: str
):
    path = listing(tmp_path, column, tie, survey, last)
    with pytest.warns(InputFileWarning) as caught:
        table = gp.read(path, kind="stations")
    assert table["md"].tolist() == [0.0, 300.0, 330.0, 360.0]
    assert table["station_type"].tolist()[0] == tie
    (told,) = [str(w.message) for w in caught]
    assert told.startswith(f"{path}:11: station at md 380.0 m left out: {last!r}")
    every = gp.read(path, kind="stations", stations="all")
    assert every["md"].tolist() == [0.0, 300.0, 330.0, 360.0, 380.0]


def test_a_listing_without_projections_reads_every_row(tmp_path: Path):
    path = listing(tmp_path, "Survey Type", "Tie-In", "Gyro NS", "Gyro NS")
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        table = gp.read(path, kind="stations")
    assert table["station_type"].tolist() == ["Tie-In", *["Gyro NS"] * 4]


def test_the_cli_integrates_no_projection(tmp_path: Path):
    path = listing(tmp_path, "Survey Type", "Tie-In", "Gyro NS", "Projection to TD")
    out = tmp_path / "out"
    spec = survey_pipeline(tmp_path)
    result = gyropipe_cli("run", spec, "--input", f"stations={path}", "--out", out, check=True)
    assert f"{path}:11: station at md 380.0 m left out" in result.stderr
    trajectory = gp.read(out / "trajectory.csv", kind="stations")
    assert trajectory["md"].max() == 360.0
    assert trajectory["station_type"].tolist() == ["Tie-In", *["Gyro NS"] * 3]
    las = lasio.read(str(out / "trajectory.las"))  # the LAS deliverable keeps them as text
    assert las["STATION_TYPE"].tolist() == ["Tie-In", *["Gyro NS"] * 3]


def test_a_listing_of_projections_only_is_refused_naming_the_column(tmp_path: Path):
    """Every row left out: no survey, refused at the file's column (was an empty table, the
    run failing later at a writer: 'the trajectory table has no rows'); stations: all reads
    them."""
    path = listing(tmp_path, "Survey Type", "PTB", "Projection to TD", "Interpolated")
    with pytest.warns(InputFileWarning), pytest.raises(InputFileError) as caught:
        gp.read(path, kind="stations")
    assert (caught.value.line, caught.value.column) == (6, "Survey Type")
    assert "no survey station: each of the 5 rows" in str(caught.value)
    assert "the reader option stations: all reads them" in str(caught.value)
    assert len(gp.read(path, kind="stations", stations="all")) == 5
    out = tmp_path / "out"
    result = gyropipe_cli("run", survey_pipeline(tmp_path), "--input", f"stations={path}",
                          "--out", out)  # fmt: skip
    assert result.returncode != 0 and not out.exists()
    assert f"{path}:6 (column 'Survey Type'): no survey station" in result.stderr


def test_many_rows_left_out_are_warned_of_ten_by_one_and_the_rest_in_one(tmp_path: Path):
    """A listing of 2,000 interpolated rows between its stations printed 2,000 warnings: the
    first ten are told at their lines, the rest counted in one warning with their lines."""
    head = "North Reference: true\nMD (m),Inc (deg),Azi (deg),Comment\n0,0,0,Tie-In\n"
    rows = [f"{300 + k * 0.5:.2f},1.00,45.00,Interpolated" for k in range(2000)]
    path = tmp_path / "many.csv"
    path.write_text(head + "\n".join(rows) + "\n1300,2,45,MWD\n")
    with pytest.warns(InputFileWarning) as caught:
        table = gp.read(path, kind="stations")
    assert table["md"].tolist() == [0.0, 1300.0]
    told = [str(w.message) for w in caught]
    assert len(told) == 11
    assert told[0].startswith(f"{path}:4: station at md 300.0 m left out: 'Interpolated'")
    assert told[-1] == f"{path}:14: 1990 more stations left out likewise (lines 14 to 2003)"
