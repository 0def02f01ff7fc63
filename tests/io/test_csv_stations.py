"""The built-in CSV plugin, exercised through its registered ReaderDef and WriterDef on real
files: header spellings, units, encodings, delimiters, title blocks, footers, every error,
writer → reader round trips and a mutation fuzz test."""

from __future__ import annotations

import datetime as dt
import json
import random
from pathlib import Path
from typing import Any

import pyarrow as pa
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pipeline as gp
from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.errors import InputFileError, InputFileWarning, UnitError
from pipeline.io import csv as csv_plugin
from pipeline.tables import PositionReadings, RawSamples, Stations
from pipeline.well import WellMetadata
from tests_support import assert_exported, byte_mutations, mutate_bytes, plugin_io

READER, WRITER = plugin_io(csv_plugin)


def put(tmp_path: Path, content: str | bytes, name: str = "survey.csv") -> Path:
    path = tmp_path / name
    path.write_bytes(content.encode() if isinstance(content, str) else content)
    return path


def read(path: Path, **options: Any) -> tuple[pa.Table, WellMetadata]:
    return READER.read(path, "stations", READER.options.model_validate(options))


def column(table: pa.Table, name: str) -> list[Any]:
    return list(table.column(name).to_pylist())


def north(table: pa.Table) -> str:
    return str(table.schema.field("azi").metadata[NORTH_KEY].decode())


def failure(path: Path, **options: Any) -> InputFileError:
    with pytest.raises(InputFileError) as info:
        read(path, **options)
    return info.value


BODY = "0,0,0\n100,1.5,45\n200,3,46.5\n"


def test_registration() -> None:
    assert READER.name == "csv"
    assert READER.kinds == {
        "stations": Stations,
        "samples": RawSamples,
        "readings": PositionReadings,
    }
    assert READER.options is csv_plugin.CsvOptions
    assert (WRITER.name, WRITER.extension) == ("csv", "csv")


@pytest.mark.parametrize(
    ("header", "ref"),
    [
        ("MD[m],INC[DEG],AZI[deg]", None),
        ("MD (m),Incl (deg),Azim (deg)", None),
        ("Measured Depth ( m ),Inclination ( deg ),Azimuth Grid ( deg )", "grid"),
        ("DEPTH [M],DEVI [DEG],HAZI [DEG]", None),
        ("DEPT(m),SDEV(deg),Azimuth True(deg)", "true"),
        ("Meas. Depth [m],Deviation [deg],Azimuth Magnetic [deg]", "magnetic"),
        ("md [m],inc [deg],Grid Azimuth [deg]", "grid"),
        ("MD [m],INC [deg],AZI (GN) [deg]", "grid"),
        ("MD [m],INC [deg],Azimuth (Grid North) [deg]", "grid"),
        ("MD [m],INC [deg],AZI [deg] (True North)", "true"),
        ("MD [m],INC [deg],AZI_MN [deg]", "magnetic"),
        ("MD [m],INC [deg],Azimuth True North [deg]", "true"),
        ("MD [m],INC [deg],AZI TN [deg],Comment", "true"),
        ('"MD [m]","INC [deg]","AZI [deg]"', None),
    ],
)
def test_header_spellings(tmp_path: Path, header: str, ref: str | None) -> None:
    extra = ",0" if "Comment" in header else ""
    body = "".join(line + extra + "\n" for line in BODY.splitlines())
    options = {} if ref else {"north_reference": "grid"}
    table, well = read(put(tmp_path, header + "\n" + body), **options)
    kinds = ["station_type"] if "Comment" in header else []  # what the row is, as text
    assert table.column_names == ["md", "inc", "azi", *kinds, "source_line"]
    assert column(table, "md") == [0.0, 100.0, 200.0]
    assert column(table, "inc") == [0.0, 1.5, 3.0]
    assert column(table, "azi") == [0.0, 45.0, 46.5]
    assert column(table, "source_line") == [2, 3, 4]
    assert north(table) == (ref or "grid")
    assert well == WellMetadata(north_reference=ref)  # the header's; the option's is not
    Stations.validate_table(table)


def test_units_in_field_metadata_and_types(tmp_path: Path) -> None:
    table, _ = read(put(tmp_path, "MD[m],INC[deg],AZI TN[deg]\n" + BODY))
    schema = table.schema
    assert [schema.field(n).type for n in table.column_names] == [pa.float64()] * 3 + [pa.int64()]
    assert schema.field("md").metadata[UNIT_KEY] == b"m"
    assert schema.field("inc").metadata[UNIT_KEY] == b"deg"
    assert schema.field("azi").metadata[UNIT_KEY] == b"deg"
    assert schema.field("source_line").metadata is None


def test_survey_column(tmp_path: Path) -> None:
    text = "Survey ID,MD[m],INC[deg],AZI TN[deg]\nS1,0,0,0\nS1,10,1,2\n S2 ,0,0,0\n,5,1,1\n"
    table, _ = read(put(tmp_path, text))
    assert table.column_names == ["survey", "md", "inc", "azi", "source_line"]
    assert column(table, "survey") == ["S1", "S1", "S2", None]


def test_feet_converted_to_metres(tmp_path: Path) -> None:
    table, _ = read(put(tmp_path, "MD (ft),INC (deg),AZI TN (deg)\n0,0,0\n1000,1,2\n100.5,1,2\n"))
    assert column(table, "md") == [0.0, 1000 * 0.3048, 100.5 * 0.3048]
    assert column(table, "md")[1] == 304.8


def test_declared_units_override_the_header(tmp_path: Path) -> None:
    path = put(tmp_path, "MD [m],INC [deg],AZI TN [deg]\n1000,3.141592653589793,0\n")
    table, _ = read(path, md_unit="ft", angle_unit="rad")
    assert column(table, "md") == [304.8]
    assert column(table, "inc") == [180.0]


def test_units_declared_only_in_options(tmp_path: Path) -> None:
    table, _ = read(put(tmp_path, "MD,INC,AZI TN\n10,1,2\n"), md_unit="FEET", angle_unit="DEGA")
    assert column(table, "md") == [10 * 0.3048]


@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
def test_line_endings(tmp_path: Path, newline: str) -> None:
    text = "# north_reference=true\nMD[m],INC[deg],AZI[deg]\n\n" + BODY + "End of survey\n"
    table, _ = read(put(tmp_path, text.replace("\n", newline)))
    assert column(table, "md") == [0.0, 100.0, 200.0]
    assert column(table, "source_line") == [4, 5, 6]
    assert north(table) == "true"


def test_byte_order_mark(tmp_path: Path) -> None:
    table, _ = read(put(tmp_path, b"\xef\xbb\xbfMD[m],INC[deg],AZI TN[deg]\r\n1,2,3\r\n"))
    assert column(table, "md") == [1.0]


def test_semicolon_with_decimal_commas_detected(tmp_path: Path) -> None:
    text = "MD [m];INC [deg];AZI TN [deg]\n0;0;0\n100,5;1,25;45\n1e3;2,5;350,75\n"
    table, _ = read(put(tmp_path, text))
    assert column(table, "md") == [0.0, 100.5, 1000.0]
    assert column(table, "azi") == [0.0, 45.0, 350.75]


def test_decimal_comma_declared(tmp_path: Path) -> None:
    table, _ = read(put(tmp_path, "MD [m]|INC [deg]|AZI TN [deg]\n1,5|2|3\n"), decimal=",")
    assert column(table, "md") == [1.5]


def test_mixed_decimal_marks_are_an_error(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD [m];INC [deg];AZI TN [deg]\n1,5;2.5;3\n"))
    assert (err.line, err.column) == (2, "MD [m]")
    assert "got '1,5'" in str(err)
    assert "decimal=','" in str(err)


def test_declared_decimal_comma_refuses_dots(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD [m];INC [deg];AZI TN [deg]\n1,5;2.5;3\n"), decimal=",")
    assert (err.line, err.column) == (2, "INC [deg]")


def test_decimal_comma_with_comma_delimiter_is_refused() -> None:
    with pytest.raises(ValueError, match="decimal ','"):
        READER.options.model_validate({"decimal": ",", "delimiter": ","})


def test_tab_delimited(tmp_path: Path) -> None:
    text = "Measured Depth (ft)\tInclination (deg)\tAzimuth Grid (deg)\n0\t0\t0\n10\t 1.5 \t20\n"
    table, _ = read(put(tmp_path, text, "survey.tsv"))
    assert column(table, "md") == [0.0, 3.048]
    assert column(table, "inc") == [0.0, 1.5]
    assert north(table) == "grid"


def test_delimiter_option(tmp_path: Path) -> None:
    table, _ = read(put(tmp_path, "MD[m]|INC[deg]|AZI TN[deg]\n1|2|3\n"), delimiter="|")
    assert column(table, "azi") == [3.0]


def test_title_block_and_footer(tmp_path: Path) -> None:
    text = (
        "ACME Gyro Services - survey report\n"
        "Generated: 2024-05-02 10:11\n"
        "# comment line\n"
        "Units as stated in the header\n"
        "\n"
        "MD (m),INC (deg),AZI (deg)\n"
        "0,0,0\n"
        "# a comment inside the data\n"
        "\n"
        "100,1,10\n"
        "200,2,20\n"
        "\n"
        "Total,,,200\n"
        "End of survey\n"
        "\n"
    )
    table, well = read(put(tmp_path, text), north_reference="true")
    assert column(table, "md") == [0.0, 100.0, 200.0]
    assert column(table, "source_line") == [7, 10, 11]
    assert well == WellMetadata()


def test_title_block_well_metadata(tmp_path: Path) -> None:
    text = (
        "Well Name: A-12\n"
        "API: 42-501-20130\n"
        "Field:,Ekofisk,,\n"
        "Operator = North Oil\n"
        "Lat: 61.25\n"
        "Long: 73.4 deg\n"
        "Elevation: 82 ft\n"
        "Survey Date: 2024-05-01\n"
        "Tool: GWD\n"
        "Serial: SN-7\n"
        "# depth_reference=RKB\n"
        "Comment: nothing to see\n"
        "Azimuth reference: Grid North\n"
        "MD (m),INC (deg),AZI (deg)\n" + BODY
    )
    table, well = read(put(tmp_path, text))
    assert well == WellMetadata(
        well="A-12",
        uwi="42-501-20130",
        field="Ekofisk",
        company="North Oil",
        latitude=61.25,
        longitude=73.4,
        elevation=82 * 0.3048,
        survey_date=dt.date(2024, 5, 1),
        tool_type="GWD",
        tool_serial="SN-7",
        depth_reference="RKB",
        north_reference="grid",
    )
    assert north(table) == "grid"


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("Latitude: 95", "invalid latitude '95'"),
        ("Latitude: north", "invalid latitude 'north'"),
        ("Elevation: 12 deg", "is an angle, expected a length"),
        ("Date: 05/01/2024", "invalid survey_date '05/01/2024'"),
        ("north_reference: sideways", "north reference 'sideways' is not one of"),
    ],
)
def test_invalid_title_values(tmp_path: Path, line: str, message: str) -> None:
    err = failure(put(tmp_path, f"Survey report\n{line}\nMD[m],INC[deg],AZI TN[deg]\n1,2,3\n"))
    assert err.line == 2
    assert message in str(err)


def test_title_survey_dates_out_of_order(tmp_path: Path) -> None:
    """The validator's refusal is the file's error at the last day's line (was the reader's
    crash, a pydantic ValidationError)."""
    title = "Survey Date: 2026-03-05\nwell.survey_date_last: 2026-03-01\n"
    err = failure(put(tmp_path, f"{title}MD[m],INC[deg],AZI TN[deg]\n1,2,3\n"))
    assert err.line == 2
    assert "survey_date_last 2026-03-01 is before survey_date 2026-03-05" in str(err)


def test_title_survey_dates_read_alike(tmp_path: Path) -> None:
    """A last day is read as the survey date is (:func:`pipeline.io.dates.header_date`:
    '05-MAR-2026'), not by pydantic's ISO-only rule."""
    title = "Survey Date: 02-MAR-2026\nwell.survey_date_last: 05-MAR-2026\n"
    _, well = read(put(tmp_path, f"{title}MD[m],INC[deg],AZI TN[deg]\n1,2,3\n"))
    assert well.survey_dates() == "2026-03-02 to 2026-03-05"


def test_title_value_given_twice(tmp_path: Path) -> None:
    text = "Well: A\nWell Name: B\nMD[m],INC[deg],AZI TN[deg]\n1,2,3\n"
    err = failure(put(tmp_path, text))
    assert err.line == 2
    assert "given twice" in str(err)


WELLPATH_REPORT = """\
WELLPATH REPORT
Well: A-12
Company: North Oil
Azimuth reference: Grid North
Elevation: 82 ft

MD [ft],Inc [deg],Azi [deg],TVD [m],+N/-S [m],+E/-W [m],DLS [deg/100ft],Comment
0.00,0.00,0.00,0.00,0.00,0.00,,tie-in
100.00,1.00,45.00,30.48,0.19,0.19,1.00,
200.00,2.50,46.00,60.94,0.94,-0.96,1.50,

End of report
"""


def test_wellpath_report_with_mixed_units(tmp_path: Path) -> None:
    table, well = read(put(tmp_path, WELLPATH_REPORT))
    assert table.column_names == [
        *("md", "inc", "azi", "station_type", "tvd", "north", "east", "dls"),
        "source_line",
    ]
    assert column(table, "station_type") == ["tie-in", None, None]  # the Comment column
    assert column(table, "md") == [0.0, 30.48, 60.96]  # ft → m
    assert column(table, "tvd") == [0.0, 30.48, 60.94]  # already m
    assert column(table, "north") == [0.0, 0.19, 0.94]
    assert column(table, "east") == [0.0, 0.19, -0.96]
    assert column(table, "dls")[0] is None  # no dogleg at the tie-in: empty cell, null
    assert column(table, "dls")[1:] == pytest.approx([30 / 30.48, 1.5 * 30 / 30.48])
    assert column(table, "source_line") == [8, 9, 10]
    units = {f.name: f.metadata[UNIT_KEY].decode() for f in table.schema if f.metadata}
    assert units == {
        **dict.fromkeys(["md", "tvd", "north", "east"], "m"),
        **dict.fromkeys(["inc", "azi"], "deg"),
        "dls": "deg/30m",
    }
    assert north(table) == "grid"
    assert (well.well, well.company, well.elevation) == ("A-12", "North Oil", 82 * 0.3048)
    Stations.validate_table(table)


def test_extra_column_units(tmp_path: Path) -> None:
    text = "MD[ft],INC[deg],AZI TN[deg],TVD\n1000,2,3,300\n"
    err = failure(put(tmp_path, text))
    assert (err.line, err.column) == (1, "TVD")
    assert "no unit for this column" in str(err)
    assert "units: {tvd: ft}" in str(err)
    table, _ = read(put(tmp_path, text), units={"tvd": "ft", "md": "m"})
    assert column(table, "tvd") == [300 * 0.3048]
    assert column(table, "md") == [1000.0]  # units: win over the header


def test_mnemonics_table_names_the_columns(tmp_path: Path) -> None:
    text = "DMEA (m),Zenith Angle (deg),AZTN (deg),Dogleg Severity (deg/30m)\n10,1,2,3\n"
    table, _ = read(put(tmp_path, text), north_reference="true")
    assert table.column_names == ["md", "inc", "azi", "dls", "source_line"]
    assert not hasattr(csv_plugin, "COLUMN_ALIASES")


def test_aliases_option(tmp_path: Path) -> None:
    text = "Bohrtiefe (m),Neigung (deg),Direction (deg),GX (m)\n10,1,2,3\n"
    aliases = {"Bohrtiefe": "md", "NEIGUNG": "inc", "gx": "north"}
    table, _ = read(put(tmp_path, text), aliases=aliases, north_reference="grid")
    assert column(table, "md") == [10.0]
    assert column(table, "azi") == [2.0]  # DIRECTION is a built-in mnemonic
    assert column(table, "north") == [3.0]  # the option wins over GX = acc_x
    with pytest.raises(ValueError, match="unknown column 'depth'"):
        READER.options.model_validate({"aliases": {"Bohrtiefe": "depth"}})


def test_header_line_option(tmp_path: Path) -> None:
    text = "MD[m],INC[deg],AZI TN[deg]\n# copy\nMD[m],INC[deg],AZI TN[deg]\n1,2,3\n"
    err = failure(put(tmp_path, text))  # found on line 1: line 3 is not a number row
    assert err.line == 3
    table, _ = read(put(tmp_path, text), header_line=3)
    assert column(table, "source_line") == [4]
    err = failure(put(tmp_path, text), header_line=4)
    assert "no header row with md, inc, azi columns on line 4 (option header_line)" in str(err)
    assert err.line == 4


def test_explicit_columns_option(tmp_path: Path) -> None:
    text = "Hole Depth (ft),Hole Angle (deg),Direction (deg),MD (m)\n100,1,2,5\n"
    columns = {"md": "hole depth", "inc": "Hole Angle (deg)", "azi": "Direction"}
    table, _ = read(put(tmp_path, text), columns=columns, north_reference="true")
    assert column(table, "md") == [30.48]
    assert column(table, "inc") == [1.0]


def test_explicit_columns_naming_one_cell_twice_are_refused(tmp_path: Path) -> None:
    """One header cell is one column: two names for it are an error of the option, at the
    header line (was a KeyError from pyarrow)."""
    text = "MD[m],INC[deg],AZI TN[deg]\n100,1,2\n"
    err = failure(put(tmp_path, text), columns={"md": "MD", "tvd": "MD[m]"})
    assert "option columns: md and tvd both name the header cell 'MD[m]'" in str(err)
    assert (err.line, err.column) == (1, "MD[m]")


def test_azimuth_column_chosen_by_north_reference(tmp_path: Path) -> None:
    path = put(tmp_path, "MD[m],INC[deg],AZI TN[deg],AZI GN[deg]\n1,2,3,4\n")
    table, _ = read(path, north_reference="grid")
    assert column(table, "azi") == [4.0]
    err = failure(path)
    assert "several columns look like azi" in str(err)
    assert err.line == 1


def test_ambiguous_depth_columns(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD[m],DEPTH[m],INC[deg],AZI TN[deg]\n1,1,2,3\n"))
    assert "several columns look like md: 'MD[m]', 'DEPTH[m]'" in str(err)


# --------------------------------------------------------------------------- errors


def test_missing_column(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "Report\nMD[m],INC[deg],Bearing[deg]\n1,2,3\n"))
    assert err.line == 2
    message = str(err)
    assert "missing column(s) azi" in message
    assert "'MD[m]', 'INC[deg]', 'Bearing[deg]'" in message
    assert "AZIMUTH" in message


def test_no_header_at_all(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "1,2,3\n4,5,6\n"))
    assert "no header row" in str(err)
    assert "MEASURED DEPTH" in str(err)


def test_non_numeric_cell(tmp_path: Path) -> None:
    text = "Title\n\nMD[m],INC[deg],AZI TN[deg]\n0,0,0\n\n100,abc,3\n200,2,3\n"
    err = failure(put(tmp_path, text))
    assert (err.line, err.column) == (6, "INC[deg]")
    assert "expected a number, got 'abc'" in str(err)
    assert str(err).startswith(f"{tmp_path / 'survey.csv'}:6 (column 'INC[deg]'):")


def test_many_non_numeric_cells_are_listed(tmp_path: Path) -> None:
    rows = "".join(f"{i},x{i},1\n" for i in range(8))
    err = failure(put(tmp_path, "MD[m],INC[deg],AZI TN[deg]\n" + rows))
    assert err.line == 2
    message = str(err)
    assert "8 bad cells" in message
    assert "'x4' (line 6)" in message
    assert "'x5'" not in message


def test_non_numeric_cell_inside_the_data_is_not_a_footer(tmp_path: Path) -> None:
    text = "MD[m],INC[deg],AZI TN[deg]\n0,0,0\nEnd of survey\n100,1,2\n"
    err = failure(put(tmp_path, text))
    assert err.line == 3


@pytest.mark.parametrize("last", ["100,1", "100", "1oo,1,2", "abc,1,2", "nan,1,2"])
def test_corrupt_last_row_is_not_a_footer(tmp_path: Path, last: str) -> None:
    err = failure(put(tmp_path, "MD[m],INC[deg],AZI TN[deg]\n0,0,0\n" + last + "\nEnd\n"))
    assert err.line == 3


def test_empty_cell(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD[m],INC[deg],AZI TN[deg]\n0,0,0\n100, ,45\n"))
    assert (err.line, err.column) == (3, "INC[deg]")
    assert "got an empty cell" in str(err)


def test_wrong_number_of_cells(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD[m],INC[deg],AZI TN[deg]\n0,0,0\n1,2,3,4\n5,6,7,8\n"))
    assert err.line == 3
    assert "expected 3 cells as in the header (line 1), got 4; 2 such rows" in str(err)


def test_unbalanced_quote(tmp_path: Path) -> None:
    err = failure(put(tmp_path, 'MD[m],INC[deg],AZI TN[deg]\n0,0,0\n"1,2,3\n4,5,6\n7,8,9\n'))
    assert err.line == 3
    assert "unbalanced double quote" in str(err)


def test_unknown_unit(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "Title\nMD[furlong],INC[deg],AZI TN[deg]\n1,2,3\n"))
    assert (err.line, err.column) == (2, "MD[furlong]")
    assert "unknown unit 'furlong'" in str(err)
    assert "md_unit" in str(err)


def test_wrong_dimension_unit(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD[m],INC[ft],AZI TN[deg]\n1,2,3\n"))
    assert err.column == "INC[ft]"
    assert "unit 'ft' is a length, expected an angle" in str(err)


def test_unknown_unit_option() -> None:
    with pytest.raises(ValueError, match="unit 'deg' is an angle, expected a length"):
        READER.options.model_validate({"md_unit": "deg"})


def test_no_unit(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD,INC[deg],AZI TN[deg]\n1,2,3\n"))
    assert (err.line, err.column) == (1, "MD")
    assert "no unit" in str(err)
    assert "md_unit" in str(err)
    err = failure(put(tmp_path, "MD[m],INC,AZI TN[deg]\n1,2,3\n"))
    assert err.column == "INC"
    assert "angle_unit" in str(err)


@pytest.mark.parametrize(
    ("text", "options"),
    [
        ("MD[m],INC[deg],AZI TN[deg]\n1,2,3\n", {"north_reference": "grid"}),
        ("north_reference: grid\nMD[m],INC[deg],AZI[deg]\n1,2,3\n", {"north_reference": "true"}),
        ("# north_reference=grid\nMD[m],INC[deg],AZI TN[deg]\n1,2,3\n", {}),
        ("# north_reference=grid\n# north_reference=true\nMD[m],INC[deg],AZI[deg]\n1,2,3\n", {}),
    ],
)
def test_conflicting_north_references(tmp_path: Path, text: str, options: dict[str, Any]) -> None:
    err = failure(put(tmp_path, text), **options)
    assert "conflicting north references: " in str(err)
    assert "grid" in str(err)
    assert "true" in str(err)


def test_no_north_reference(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD[m],INC[deg],AZI[deg]\n1,2,3\n"))
    assert (err.line, err.column) == (1, "AZI[deg]")
    assert "no north reference" in str(err)
    assert "north_reference" in str(err)


@pytest.mark.parametrize("content", [b"", b"\n\n  \r\n", b"\xef\xbb\xbf"])
def test_empty_file(tmp_path: Path, content: bytes) -> None:
    assert "empty" in str(failure(put(tmp_path, content)))


def test_header_without_data(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD[m],INC[deg],AZI TN[deg]\n\nEnd of survey\n"))
    assert "no data rows" in str(err)


def test_binary_garbage(tmp_path: Path) -> None:
    garbage = bytes(random.Random(7).randrange(256) for _ in range(4096))
    failure(put(tmp_path, garbage))


def test_invalid_utf8_names_its_line(tmp_path: Path) -> None:
    err = failure(put(tmp_path, b"MD[m],INC[deg],AZI TN[deg]\n1,2,3\n4,\xff,6\n"))
    assert err.line == 3
    assert "not UTF-8" in str(err)


def test_nul_byte(tmp_path: Path) -> None:
    err = failure(put(tmp_path, b"MD[m],INC[deg],AZI TN[deg]\r\n1,2,3\r\n4,\x00,6\r\n"))
    assert err.line == 3


def test_missing_file(tmp_path: Path) -> None:
    assert "cannot read" in str(failure(tmp_path / "absent.csv"))


def test_other_kinds_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="reads kinds stations, samples, readings"):
        READER.read(put(tmp_path, "x"), "trajectory", None)


# ---------------------------------------------------------------------------- sniff


def test_sniff(tmp_path: Path) -> None:
    for name in ("a.csv", "b.TXT", "c.tsv"):
        assert READER.sniff(put(tmp_path, "anything", name))
    assert READER.sniff(put(tmp_path, "Title\nMD[m];INC[deg];AZI[deg]\n1;2;3\n", "s.dat"))
    assert not READER.sniff(put(tmp_path, "~Version\nVERS. 2.0\n", "s.las"))
    assert not READER.sniff(put(tmp_path, bytes(range(256)) * 300, "s.bin"))
    assert not READER.sniff(tmp_path / "absent.dat")
    assert not READER.sniff(tmp_path)


# --------------------------------------------------------------------------- writer


def _stations(md: list[float], inc: list[float], azi: list[float], ref: str) -> pa.Table:
    surveys = ["S1"] * len(md)
    data = {"survey": surveys, "md": md, "inc": inc, "azi": azi}
    return Stations.compiled().make_table(data, north_reference=ref)


WELL = WellMetadata(
    well="A-12, side track",
    uwi="42-501-20130",
    company="North Oil",
    latitude=61.25,
    longitude=73.4,
    elevation=24.9936,
    depth_reference="RKB",
    survey_date=dt.date(2024, 5, 1),
    tool_type="GWD: north-seeking",
    tool_serial="SN=7",
    north_reference="true",
)

_md = st.floats(0.0, 15_000.0, width=64)  # m
_inc = st.floats(0.0, 180.0, width=64)  # deg
# deg; in the last half step below 360 an azimuth is written 359.999999, not 360 (a full step
# off by design: io/precision.py), which test_writer_keeps_azimuths_below_a_full_turn states
_azi = st.floats(0.0, 360.0 - 1e-6, width=64)


@settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(  # real surveys' values: a null marker (-999.25 …) or an impossible angle is refused
    rows=st.lists(st.tuples(_md, _inc, _azi), min_size=1, max_size=30),
    ref=st.sampled_from(["true", "grid", "magnetic"]),
)
def test_round_trip(tmp_path: Path, rows: list[tuple[float, float, float]], ref: str) -> None:
    md, inc, azi = (list(c) for c in zip(*rows, strict=True))
    table = _stations(md, inc, azi, ref)
    path = tmp_path / "out.csv"
    WRITER.write(table, path, WELL)
    back, well = read(path)
    assert well == WELL.merged({"north_reference": ref})  # the azimuths' north is the well's
    assert back.schema.field("azi").metadata == table.schema.field("azi").metadata
    for name in ("md", "inc", "azi"):
        assert back.schema.field(name).metadata == table.schema.field(name).metadata
    assert_exported(back, table, ["md", "inc", "azi"])
    assert column(back, "survey") == column(table, "survey")


def test_writer_keeps_azimuths_below_a_full_turn(tmp_path: Path) -> None:
    table = _stations([0.0, 10.0], [0.0, 5.0], [359.9999999999999, 359.9999996], "true")
    path = tmp_path / "out.csv"
    WRITER.write(table, path, WELL)
    assert path.read_text().splitlines()[-2:] == ['"S1",0,0,359.999999', '"S1",10,5,359.999999']


def test_writer_format(tmp_path: Path) -> None:
    """Values at their unit's decimals (md 4, angles 6): no float noise, no −0."""
    table = _stations([0.0, 914.4000000000001], [-0.0, 1 / 3], [359.5, 1e-300], "grid")
    path = tmp_path / "out.csv"
    WRITER.write(table, path, WellMetadata(well="A-1", survey_date=dt.date(2024, 5, 1)))
    assert path.read_text().splitlines() == [
        "# gyropipe A-1",
        "# north_reference=grid",
        "# well.well=A-1",
        "# well.survey_date=2024-05-01",
        "survey,md[m],inc[deg],azi[deg]",
        '"S1",0,0,359.5',
        '"S1",914.4,0.333333,0',
    ]


def test_writer_any_table(tmp_path: Path) -> None:
    table = pa.table({"name": ["a,b", 'q"'], "count": [1, 2], "ok": [True, None]})
    path = tmp_path / "any.csv"
    WRITER.write(table, path, WellMetadata())
    assert path.read_text().splitlines() == [
        "# gyropipe -",
        "name,count,ok",
        '"a,b",1,true',
        '"q""",2,',
    ]


def test_writer_refuses_what_it_cannot_write(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="line break"):
        WRITER.write(
            _stations([1.0], [2.0], [3.0], "true"), tmp_path / "x.csv", WellMetadata(well="a\nb")
        )
    grid = pa.field("b", pa.float64(), metadata={NORTH_KEY: b"grid"})
    true = pa.field("a", pa.float64(), metadata={NORTH_KEY: b"true"})
    table = pa.Table.from_arrays([pa.array([1.0]), pa.array([2.0])], schema=pa.schema([true, grid]))
    with pytest.raises(ValueError, match="different north references"):
        WRITER.write(table, tmp_path / "y.csv", WellMetadata())


# ----------------------------------------------------------------------------- fuzz

VALID = (
    b"Well: A-12\n# north_reference=grid\nMD (ft);INC [deg];Azimuth Grid (deg);Survey\n"
    b"0;0;0;S1\n100,5;1,25;45;S1\n200;2,5;46;S1\nEnd of survey\n"
)
_mutation = byte_mutations(len(VALID), b',;\t|"\r\n#:=[]()e.- ')


def test_valid_fuzz_seed_parses(fuzz_dir: Path) -> None:
    table, well = read(put(fuzz_dir, VALID))
    assert column(table, "md") == [0.0, 100.5 * 0.3048, 200 * 0.3048]
    assert well.well == "A-12"


@settings(max_examples=400, deadline=None, derandomize=True)
@given(mutations=st.lists(_mutation, min_size=1, max_size=4))
def test_fuzz_mutations_raise_typed_errors_only(
    fuzz_dir: Path, mutations: list[tuple[str, int, int]]
) -> None:
    path = put(fuzz_dir, mutate_bytes(VALID, mutations))
    try:
        table, _ = read(path)
    except (InputFileError, UnitError):
        return
    assert table.num_rows >= 1
    assert table.column_names[-4:] == ["md", "inc", "azi", "source_line"]


def test_map_northing_and_easting_are_not_displacements(tmp_path: Path) -> None:
    listing = (  # as survey software lists a well: local displacements, then map coordinates
        "MD [m],Inc [deg],Azi True [deg],TVD [m],+N/-S [m],+E/-W [m],Northing [m],Easting [m]\n"
        "0,0,0,0,0,0,6478512.25,431250.50\n"
        "100,10,45,99.49,6.15,6.15,6478518.40,431256.65\n"
    )
    frame = gp.read(put(tmp_path, listing), kind="stations")
    assert frame["north"].tolist() == [0.0, 6.15]
    assert frame["east"].tolist() == [0.0, 6.15]
    only_map = (
        "MD [m],Inc [deg],Azi True [deg],TVD [m],Northing [m],Easting [m]\n"
        "0,0,0,0,6478512.25,431250.50\n"
        "100,10,45,99.49,6478518.40,431256.65\n"
    )
    frame = gp.read(put(tmp_path, only_map), kind="stations")
    assert "north" not in frame.columns and "east" not in frame.columns


GRID_LISTING = "Well: TEST-1\nMD (ft),Inc (deg),Azi Grid (deg)\n0,0,0\n1000,5,45\n2000,10,47\n"


def test_azimuths_named_grid_make_the_well_grid(tmp_path: Path) -> None:
    """A listing whose azimuth column says grid north, run through a pipeline whose ``well:``
    says true north (survey.yaml): the run's well and every file written state grid — the
    azimuths' own north, as an LAS NREF would — never the pipeline's true beside grid
    azimuths."""
    from tests_support import gyropipe_cli

    listing = put(tmp_path, GRID_LISTING)
    out = tmp_path / "out"
    gyropipe_cli(
        "run", "pipelines/survey.yaml", "--input", f"stations={listing}", "--out", out, check=True
    )
    assert json.loads((out / "run.json").read_text())["well"]["north_reference"] == "grid"
    text = (out / "trajectory.csv").read_text()
    assert "# well.north_reference=grid\n" in text and "north_reference=true" not in text
    for name in ("trajectory.csv", "trajectory.xml", "trajectory.las"):
        frame = gp.read(out / name)
        assert frame.attrs["well"]["north_reference"] == "grid", name
        assert frame.attrs["north_reference"] == "grid", name


def test_well_north_reference_contradicting_the_azimuths_is_overruled(tmp_path: Path) -> None:
    """A ``well.north_reference`` title line saying true above azimuths declared grid (as
    gyropipe's CSV writer wrote them before): the azimuths' north is the well's, with a
    warning at the header line."""
    text = "# north_reference=grid\n# well.north_reference=true\nMD[m],INC[deg],AZI[deg]\n1,2,3\n"
    path = put(tmp_path, text)
    with pytest.warns(InputFileWarning, match=r"survey\.csv:3: well\.north_reference 'true'"):
        table, well = read(path)
    assert well.north_reference == "grid" and north(table) == "grid"


def test_a_north_override_contradicting_the_file_is_refused(tmp_path: Path) -> None:
    """``--well north_reference=true`` over a listing whose azimuths say grid would state a
    north the azimuths are not in (the override is the readers' default only): refused,
    naming the file; over a listing naming no north it is the azimuths' north."""
    from tests_support import gyropipe_cli

    listing = put(tmp_path, GRID_LISTING)
    run = ("run", "pipelines/survey.yaml", "--input", f"stations={listing}")
    refused = gyropipe_cli(*run, "--well", "north_reference=true", "--out", tmp_path / "a")
    assert refused.returncode != 0 and not (tmp_path / "a").exists()
    assert f"{listing}: the file names grid north for its azimuths" in refused.stderr
    assert "override north_reference=true contradicts it" in refused.stderr
    silent = put(tmp_path, GRID_LISTING.replace("Azi Grid", "Azi"), "silent.csv")
    out = tmp_path / "b"
    gyropipe_cli(
        "run", "pipelines/survey.yaml", "--input", f"stations={silent}",
        "--well", "north_reference=grid", "--out", out, check=True,
    )  # fmt: skip
    assert gp.read(out / "trajectory.csv").attrs["north_reference"] == "grid"
    assert json.loads((out / "run.json").read_text())["well"]["north_reference"] == "grid"
