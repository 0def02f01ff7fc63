"""Surveys written by gyropipe and read back by it: the same numbers in the same units, the
same north reference, whatever way the table came to the writer (a hand-made DataFrame, an
Arrow table whose well names the north)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pyarrow as pa
import pytest

import pipeline as gp
from pipeline.contracts import UNIT_KEY
from pipeline.errors import InputFileError
from pipeline.well import WellMetadata, attach

EXTENSIONS = ("las", "csv", "xml", "parquet")


def _stations() -> pd.DataFrame:
    return pd.DataFrame(
        {"md": [0.0, 150.0, 300.0], "inc": [0.0, 4.5, 9.0], "azi": [0.0, 212.0, 214.5]}
    )


@pytest.mark.parametrize("ext", EXTENSIONS)
def test_a_frames_north_reference_and_canonical_units_are_written(tmp_path: Path, ext: str) -> None:
    """The API's own rule for a DataFrame (attrs['north_reference'] names the azimuths'
    north, a column declaring no unit is in its canonical one) is what the file states: the
    north was dropped (a LAS with an empty NREF, a CSV with none) and inc/azi written
    without a unit ('INC .', 'inc,azi')."""
    frame = _stations()
    frame.attrs = {"north_reference": "grid", "well": {"well": "A-7"}}
    path = gp.write(frame, tmp_path / f"survey.{ext}")
    back = gp.read(path, kind="stations")
    assert back.attrs["north_reference"] == "grid"
    assert back.attrs["units"]["inc"] == back.attrs["units"]["azi"] == "deg"
    assert back.attrs["units"]["md"] == "m"
    assert back["azi"].tolist() == [0.0, 212.0, 214.5]


def test_an_arrow_tables_azimuths_take_the_wells_north(tmp_path: Path) -> None:
    """An Arrow table whose azimuths carry no north of their own but whose well names one,
    written to CSV: its north_reference line states it (only well.north_reference was
    written, which the reader rightly does not take for the azimuths')."""
    unit = {UNIT_KEY: b"m"}
    table = pa.table(
        {"md": [0.0, 150.0, 300.0], "inc": [0.0, 4.5, 9.0], "azi": [0.0, 212.0, 214.5]}
    )
    fields = [table.schema.field("md").with_metadata(unit)] + [
        table.schema.field(n).with_metadata({UNIT_KEY: b"deg"}) for n in ("inc", "azi")
    ]
    table = attach(
        pa.Table.from_arrays(table.columns, schema=pa.schema(fields)),
        WellMetadata(well="A-7", north_reference="true"),
    )
    path = gp.write(table, tmp_path / "survey.csv")
    assert "# north_reference=true\n" in path.read_text()
    assert gp.read(path, kind="stations").attrs["north_reference"] == "true"


def test_a_las_keeps_the_tool_preset_and_the_geomagnetic_reference(tmp_path: Path) -> None:
    """Raw samples converted to LAS and read back keep the well's tool_preset (the tool
    catalogue entry whose error magnitudes compassing takes: without it σ_azi came from the
    undeclared tool's model) and its geomagnetic field and dip (the magnetometer checks'
    reference): all three were lost."""
    well = WellMetadata(
        well="A-7",
        latitude=61.25,
        tool_preset="mems-vrg",
        magnetic_field=59731.0,
        magnetic_dip=78.29,
    )
    units = {"time": b"s", "gyro_x": b"deg/h", "acc_x": b"m/s2", "acc_y": b"m/s2", "acc_z": b"m/s2"}
    table = pa.table({name: [0.0, 0.01, 0.02] for name in units})
    fields = [table.schema.field(n).with_metadata({UNIT_KEY: u}) for n, u in units.items()]
    samples = attach(pa.Table.from_arrays(table.columns, schema=pa.schema(fields)), well)
    path = gp.write(samples, tmp_path / "samples.las")
    back = gp.read(path, kind="samples").attrs["well"]
    assert (back["tool_preset"], back["magnetic_field"], back["magnetic_dip"]) == (
        "mems-vrg",
        59731.0,
        78.29,
    )


@pytest.mark.parametrize("ext", ["csv", "xml"])
def test_a_writer_refuses_a_value_that_reads_back_as_no_value(tmp_path: Path, ext: str) -> None:
    """A displacement of -999.25 m written to CSV or WITSML read back as a null (every
    reader takes the marker for no value): refused, as the LAS writer refuses it."""
    frame = _stations().assign(north=[0.0, -500.0, -999.25])
    frame.attrs = {"north_reference": "true"}
    with pytest.raises(gp.GyropipeError, match=r"column 'north' holds a null marker"):
        gp.write(frame, tmp_path / f"survey.{ext}")
    assert not (tmp_path / f"survey.{ext}").exists()


@pytest.mark.parametrize("ext", ["csv", "las"])
def test_a_read_files_line_numbers_are_not_written(tmp_path: Path, ext: str) -> None:
    """A survey read from a CSV (its rows from line 3 on) written again: the copy held a
    ``source_line`` column of the first file's lines (CSV), a number that means nothing in
    it; LAS left it out. Neither writes it; the copy's own lines are read back."""
    source = tmp_path / "report.csv"
    source.write_text(
        "# north_reference=true\nmd[m],inc[deg],azi[deg]\n0,0,0\n150,4.5,212\n300,9,214.5\n"
    )
    read = gp.read(source, kind="stations")
    assert read["source_line"].tolist() == [3, 4, 5]
    path = gp.write(read, tmp_path / f"copy.{ext}")
    assert "source_line" not in path.read_text().lower()
    back = gp.read(path, kind="stations")
    assert back["md"].tolist() == [0.0, 150.0, 300.0]
    assert back["source_line"].tolist() != [3, 4, 5]


def test_a_las_keeps_the_wellheads_map_coordinates_and_text_fields(tmp_path: Path) -> None:
    """A LAS lost the wellhead's map coordinates, CRS, wellbore, tool name, run and job
    numbers that CSV and WITSML keep: a report from a LAS input had none of them."""
    frame = _stations()
    given = {
        "well": "A-7",
        "wellbore": "A-7 ST1",
        "crs": "EPSG:23031",
        "easting": 512345.25,
        "northing": 6712345.5,
        "tool_name": "Gyro-X 2",
        "run_number": "3",
        "job_number": "J-1024",
    }
    frame.attrs = {"north_reference": "grid", "well": given}
    back = gp.read(gp.write(frame, tmp_path / "survey.las"), kind="stations")
    assert {k: back.attrs["well"].get(k) for k in given} == given


@pytest.mark.parametrize(
    ("item", "easting"),
    [("XCOORD.FT  1640000", 1640000 * 0.3048), ("EASTING.M  512345.25", 512345.25)],
)
def test_a_las_map_coordinate_is_read_in_its_unit(tmp_path: Path, item: str, easting: float):
    source = tmp_path / "survey.las"
    source.write_text(
        "~Version\n VERS.  2.0 : LAS\n WRAP.  NO :\n"
        f"~Well\n STRT.FT 0 :\n STOP.FT 200 :\n STEP.FT 100 :\n NULL. -999.25 :\n {item} :\n"
        "~Curve\n DEPT.FT : measured depth\n INC.DEG : inclination\n AZI.DEG : grid azimuth\n"
        "~A\n0 0 0\n100 10 45\n200 20 45\n"
    )
    assert gp.read(source, kind="stations").attrs["well"]["easting"] == pytest.approx(easting)


def test_a_las_map_coordinate_without_a_unit_beside_feet_is_refused(tmp_path: Path) -> None:
    """Depths in feet do not tell a unitless easting's unit (US survey or international
    feet, 4 ft apart at 2,000,000 ft): refused at its line, not guessed."""
    source = tmp_path / "survey.las"
    source.write_text(
        "~Version\n VERS.  2.0 : LAS\n WRAP.  NO :\n"
        "~Well\n STRT.FT 0 :\n STOP.FT 200 :\n STEP.FT 100 :\n NULL. -999.25 :\n X.  2000000 :\n"
        "~Curve\n DEPT.FT : measured depth\n INC.DEG : inclination\n AZI.DEG : grid azimuth\n"
        "~A\n0 0 0\n100 10 45\n200 20 45\n"
    )
    with pytest.raises(InputFileError, match="US survey or international feet") as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == 9
