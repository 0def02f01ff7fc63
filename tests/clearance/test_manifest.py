"""The offset-well manifest: what it reads (units in the header converted) and every bad
manifest refused with its file and line, through the reader and through `gyropipe run`."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from iscwsa_support import run_clearance, write_set

from pipeline.anticollision.models import resolve_model
from pipeline.errors import InputFileError
from pipeline.io.offset_manifest import read_offset_manifest
from tests_support import ROOT

HEADER = "well_id,file,model,hole_diameter (in),north (m),east (ft),tvd (m)"


def manifest(tmp_path: Path, *lines: str, header: str = HEADER) -> Path:
    path = tmp_path / "offsets.csv"
    path.write_text("\n".join(["# offset wells", header, *lines]) + "\n", encoding="utf-8")
    return path


def test_reads_wells_with_units_converted(tmp_path: Path):
    path = manifest(
        tmp_path,
        "A-1,a.csv,iscwsa-mwd-rev4,12.25,10,100,",
        "A-2,sub/b.csv,GYRO-NS,8.5,-5,0,3.5",
        "A-3,c.csv,GYRO-NS,8.5,-5,0,-999.25",
    )
    first, second, third = read_offset_manifest(path, resolve_model)
    assert (first.well_id, first.model, first.line) == ("A-1", "ISCWSA-MWD-REV4", 3)
    assert first.file == (tmp_path / "a.csv").resolve()
    assert first.hole_diameter == pytest.approx(12.25 * 0.0254)
    assert (first.north, first.east, first.tvd) == (10.0, pytest.approx(30.48), None)
    assert second.file == (tmp_path / "sub" / "b.csv").resolve()
    assert (second.north, second.east, second.tvd) == (-5.0, 0.0, 3.5)
    assert third.tvd is None  # a null marker: no value, the first station's MD


@pytest.mark.parametrize(
    ("header", "lines", "line", "words"),
    [
        (HEADER, ["A,a.csv,MWD-REV9,12,0,0,"], 3, "unknown tool model 'MWD-REV9'"),
        (HEADER, ["A,a.csv,GYRO-NS,12,0,0,", "A,b.csv,GYRO-NS,12,0,0,"], 4, "already listed"),
        (HEADER, ["A,a.csv,GYRO-NS,twelve,0,0,"], 3, "hole_diameter: not a number"),
        (HEADER, ["A,a.csv,GYRO-NS,,0,0,"], 3, "hole_diameter must be given"),
        (HEADER, ["A,a.csv,GYRO-NS,12,nan,0,"], 3, "north: not a finite number"),
        (HEADER, ["A,a.csv,GYRO-NS,12,0"], 3, "5 cells, the header has 7"),
        (HEADER, ["A,,GYRO-NS,12,0,0,"], 3, "must not be empty"),
        ("well_id,file,model,hole_diameter", ["A,a.csv,GYRO-NS,12"], 2, "needs its unit"),
        ("well_id,file,model,hole_diameter (kg)", ["A,a.csv,GYRO-NS,12"], 2, "expected a length"),
        ("well_id,file,model,hole (in)", ["A,a.csv,GYRO-NS,12"], 2, "unknown column 'hole (in)'"),
        ("well_id,model,hole_diameter (in)", ["A,GYRO-NS,12"], 2, "missing column(s) file"),
        (HEADER, [], 2, "no offset wells listed"),
        (HEADER, ["A,a.csv,GYRO-NS,12,,5,"], 3, "north is empty or a null marker: expected"),
        (HEADER, ["A,a.csv,GYRO-NS,12,5,-9999.25,"], 3, "east is empty or a null marker"),
        (HEADER, ["A,a.csv,GYRO-NS,-999.25,5,5,"], 3, "hole_diameter must be given"),
        # once joined into the well 'AB' of file 'a.csv', the next rows' lines miscounted
        (HEADER, ['"A\nB",a.csv,GYRO-NS,12,0,0,'], 3, "a line break in 'A\\nB'"),
        (HEADER, ['A,"a.\ncsv",GYRO-NS,12,0,0,'], 3, "(a quoted cell spans lines)"),
        (
            "well_id,file,model,hole_diameter (in)",
            ["A,a.csv,GYRO-NS,12"],
            2,
            "column(s) north, east",
        ),
    ],
)
def test_bad_manifest_is_located(
    tmp_path: Path, header: str, lines: list[str], line: int, words: str
):
    path = manifest(tmp_path, *lines, header=header)
    with pytest.raises(InputFileError) as caught:
        read_offset_manifest(path, resolve_model)
    assert words in str(caught.value)
    assert str(caught.value).startswith(f"{path}:") or not lines
    if lines:
        assert caught.value.line == line


def test_well_on_the_reference_slot_says_so_with_zero(tmp_path: Path):
    """0,0 is an explicit position (a sidetrack or re-entry from the reference's slot)."""
    (entry,) = read_offset_manifest(manifest(tmp_path, "A,a.csv,GYRO-NS,8.5,0,0,"), resolve_model)
    assert (entry.north, entry.east) == (0.0, 0.0)


@pytest.mark.parametrize(
    ("second", "words"),
    [
        ("offsets/no-such.csv,ISCWSA-MWD-REV4,24,100,0,", "(column 'file'): no stations file"),
        # an empty slot once placed the well at the reference wellhead and the run said ok
        (
            "offsets/offset-02.csv,ISCWSA-MWD-REV4,24,,,",
            "(column 'north'): north is empty or a null marker: expected the slot's north from "
            "the reference wellhead (a length; 0,0 for a well on the reference's own slot)",
        ),
        # a database export's null: the well was placed 999.25 m south and the scan said ok
        (
            "offsets/offset-02.csv,ISCWSA-MWD-REV4,24,-999.25,0,",
            "(column 'north'): north is empty or a null marker",
        ),
    ],
)
def test_bad_row_fails_the_run_naming_manifest_and_line(tmp_path: Path, second: str, words: str):
    shutil.copytree(ROOT / "examples" / "clearance" / "offsets", tmp_path / "offsets")
    path = manifest(
        tmp_path,
        "offset-01,offsets/offset-01.csv,ISCWSA-MWD-REV4,24,0,100,",
        f"offset-02,{second}",
    )
    result = run_clearance(path, tmp_path / "out", "clearance.reference_model=ISCWSA-MWD-REV4")
    assert result.returncode != 0
    assert f"{path}:4 {words}" in result.stderr
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "out" / "run.json").exists()


def test_reads_the_parent_and_kickoff_columns(tmp_path: Path):
    """``parent`` names the wellbore a sidetrack left, ``kickoff_md`` its kick-off MD on the
    reference (a length; naming it names the reference as parent)."""
    path = manifest(
        tmp_path,
        "A,a.csv,GYRO-NS,8.5,0,0,,reference,3000",
        "B,b.csv,GYRO-NS,8.5,0,0,,,1000",
        "C,c.csv,GYRO-NS,8.5,5,0,,,",
        header=f"{HEADER},parent,kickoff_md (ft)",
    )
    a, b, c = read_offset_manifest(path, resolve_model)
    assert (a.parent, a.kickoff_md) == ("reference", pytest.approx(914.4))
    assert (b.parent, b.kickoff_md) == ("reference", pytest.approx(304.8))
    assert (c.parent, c.kickoff_md) == (None, None)


@pytest.mark.parametrize(
    ("cells", "words"),
    [
        ("A-9,900", "offset well '10 - well': parent 'A-9' is not the reference well"),
        (",2000", "at its kick-off MD 2000 m it is 145.789 m from the reference path"),
        (",2500", "'10 - well': kick-off MD 2500 m is outside the offset's stations"),
    ],
)
def test_bad_sidetrack_fails_the_run_naming_the_well(tmp_path: Path, cells: str, words: str):
    write_set(tmp_path / "set")
    path = manifest(
        tmp_path / "set",
        f"10 - well,offset-10.csv,ISCWSA-MWD-REV4,24,0,0,900,{cells}",
        header="well_id,file,model,hole_diameter (in),north (m),east (m),tvd (m),parent,"
        "kickoff_md (m)",
    )
    result = run_clearance(path, tmp_path / "out", "clearance.reference_model=ISCWSA-MWD-REV4")
    assert result.returncode != 0
    assert words in result.stderr
    assert "Traceback" not in result.stderr


def test_reads_the_declination_and_convergence_columns(tmp_path: Path):
    """Angles, deg east positive (an angle unit in the header optional); empty or a null
    marker (of an angle: either sign) is no value."""
    path = manifest(
        tmp_path,
        "A,a.csv,GYRO-NS,8.5,0,0,,2.5,-0.75",
        "B,b.csv,GYRO-NS,8.5,5,0,,,999.25",
        header=f"{HEADER},declination,convergence (rad)",
    )
    a, b = read_offset_manifest(path, resolve_model)
    assert (a.declination, a.convergence) == (2.5, pytest.approx(-42.971834635))
    assert (b.declination, b.convergence) == (None, None)


@pytest.mark.parametrize(
    ("column", "cell", "words"),
    [
        ("declination (m)", "2", "column 'declination': unit 'm' is a length"),
        ("declination", "east", "declination: not a number: 'east'"),
        ("declination", "1_5", "declination: not a number: '1_5'"),  # Python's 15
        ("convergence (rad)", "3.2", r"convergence: 3.2 \(183.346°\) is not within ±180°"),
        ("convergence (deg)", "181", "convergence: 181 is not within ±180°"),
    ],
)
def test_bad_angle_column_is_located(tmp_path: Path, column: str, cell: str, words: str):
    path = manifest(tmp_path, f"A,a.csv,GYRO-NS,8.5,0,0,,{cell}", header=f"{HEADER},{column}")
    with pytest.raises(InputFileError, match=words):
        read_offset_manifest(path, resolve_model)
