"""The built-in LAS plugin, exercised through its registered ReaderDef and WriterDef on real
files: header semantics, unit spellings, LAS 1.2/2.0/3.0 and wrapped layouts, nulls,
encodings, station listings and raw-sensor logs, every error, the fast path against the
careful path and lasio, writer → reader round trips and a mutation fuzz test."""

from __future__ import annotations

import datetime as dt
import logging
import math
from pathlib import Path
from typing import Any

import lasio
import numpy as np
import pyarrow as pa
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.errors import InputFileError, UnitError, WrongKindError
from pipeline.io import las as las_plugin
from pipeline.io import threads as io_threads
from pipeline.io.las import fast as las_fast
from pipeline.io.las import header as las_header
from pipeline.io.las import rows as las_rows
from pipeline.io.las.options import LasOptions
from pipeline.io.nulls import ANGLE_NULL_MARKERS, NULL_MARKERS
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.tables import LogTable, RawSamples, Stations
from pipeline.units import QUANTITIES, conversion_factor
from pipeline.well import WellMetadata
from tests_support import assert_exported, byte_mutations, mutate_bytes, plugin_io

logging.getLogger("lasio").setLevel(logging.CRITICAL)


READER, WRITER = plugin_io(las_plugin)

STATION_CURVES = " DEPT.M : depth\n INCL.DEG : inclination\n AZIM.DEG : azimuth (grid north)\n"
STATION_DATA = "0 0 0\n100 1.5 45\n200 3 46.5\n"
SAMPLE_UNITS = {"TIME": "S", "GX": "M/S2", "GY": "M/S2", "GZ": "M/S2", "WX": "DEG/HR"}
SAMPLE_CURVES = "".join(f" {m}.{u} : {m.lower()}\n" for m, u in SAMPLE_UNITS.items())
SAMPLE_DATA = "0.00 0.1 0.2 9.8 5\n0.01 0.1 0.2 9.8 6\n0.02 0.1 0.2 9.8 7\n"


def las(
    curves: str = STATION_CURVES,
    data: str = STATION_DATA,
    well: str = "",
    *,
    version: str = "2.0",
    wrap: str = "NO",
    null: str = "-999.25",
    parameters: str = "",
) -> str:
    """A LAS file: ~V, ~W (NULL then ``well`` lines), ~C, ~P (if any), ~A."""
    text = f"~Version\n VERS. {version} : version\n WRAP. {wrap} : wrap\n"
    text += f"~Well\n NULL. {null} : null value\n{well}~Curve\n{curves}"
    if parameters:
        text += f"~Parameter\n{parameters}"
    return text + f"~A\n{data}"


def data_line(text: str) -> int:
    """1-based line of the first data row of a file made by :func:`las`."""
    return text.splitlines().index("~A") + 2


def put(tmp_path: Path, content: str | bytes, name: str = "log.las") -> Path:
    path = tmp_path / name
    path.write_bytes(content.encode() if isinstance(content, str) else content)
    return path


def read(path: Path, kind: str = "stations", **options: Any) -> tuple[pa.Table, WellMetadata]:
    return READER.read(path, kind, READER.options.model_validate(options))


def failure(path: Path, kind: str = "stations", **options: Any) -> InputFileError:
    with pytest.raises(InputFileError) as info:
        read(path, kind, **options)
    return info.value


def column(table: pa.Table, name: str) -> list[Any]:
    return list(table.column(name).to_pylist())


def unit(table: pa.Table, name: str) -> str:
    return str(table.schema.field(name).metadata[UNIT_KEY].decode())


def north(table: pa.Table) -> str:
    return str(table.schema.field("azi").metadata[NORTH_KEY].decode())


def as_nan(table: pa.Table, name: str) -> np.ndarray:
    values: np.ndarray = table.column(name).to_numpy(zero_copy_only=False).astype(float)
    return values


# --------------------------------------------------------------------------- basics


def test_registration() -> None:
    assert READER.name == "las"
    assert READER.kinds == {"stations": Stations, "samples": RawSamples, "log": LogTable}
    assert READER.options is LasOptions
    assert (WRITER.name, WRITER.extension) == ("las", "las")


def test_reads_stations(tmp_path: Path) -> None:
    text = las()
    table, well = read(put(tmp_path, text))
    assert table.column_names == ["md", "inc", "azi", "source_line"]
    assert column(table, "md") == [0.0, 100.0, 200.0]
    assert column(table, "inc") == [0.0, 1.5, 3.0]
    assert column(table, "azi") == [0.0, 45.0, 46.5]
    first = data_line(text)
    assert column(table, "source_line") == [first, first + 1, first + 2]
    assert [unit(table, n) for n in ("md", "inc", "azi")] == ["m", "deg", "deg"]
    assert table.schema.field("source_line").type == pa.int64()
    assert north(table) == "grid"
    assert well == WellMetadata(north_reference="grid")
    Stations.validate_table(table)


def test_unrecognised_curves_are_left_out(tmp_path: Path) -> None:
    curves = STATION_CURVES + " GR.GAPI : gamma ray\n TEXT. : comment\n"
    data = "0 0 0 45.5 abc\n100 1.5 45 50 def\n200 3 46.5 -999.25 ghi\n"
    table, _ = read(put(tmp_path, las(curves, data)))
    assert table.column_names == ["md", "inc", "azi", "source_line"]
    assert column(table, "azi") == [0.0, 45.0, 46.5]


def test_other_kinds_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="reads kinds"):
        READER.read(put(tmp_path, las()), "trajectory", None)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"columns": {"depth": "DEPT"}}, "unknown column"),
        ({"units": {"md": "furlong"}}, "unknown unit"),
        ({"units": {"survey": "m"}}, "with a unit"),
        ({"null_values": [math.nan]}, "finite"),
        ({"colour": "red"}, "Extra inputs"),
    ],
)
def test_invalid_options(options: dict[str, Any], message: str) -> None:
    with pytest.raises(ValidationError, match=message):
        READER.options.model_validate(options)


def test_sniff(tmp_path: Path) -> None:
    assert READER.sniff(put(tmp_path, las(), "a.las"))
    assert READER.sniff(put(tmp_path, b"\xef\xbb\xbf\n# made by X\n\n  ~VERSION\n", "b.txt"))
    assert not READER.sniff(put(tmp_path, "MD,INC,AZI\n0,0,0\n", "c.csv"))
    assert READER.sniff(put(tmp_path, "~Well\n~Version\n", "d.las"))  # ~V, ~W, ~C or ~A
    assert READER.sniff(put(tmp_path, "# barebones\n~A\n1 2\n", "g.las"))
    assert not READER.sniff(put(tmp_path, "~Tops\n", "h.las"))
    assert not READER.sniff(put(tmp_path, bytes(range(256)), "e.bin"))
    assert not READER.sniff(put(tmp_path, b"", "f.las"))
    assert not READER.sniff(tmp_path / "missing.las")
    assert not READER.sniff(tmp_path)


# ------------------------------------------------------------------- header semantics

FULL_WELL = """\
 STRT.M      0.0 : start
 STOP.M    200.0 : stop
 STEP.M    100.0 : step
 COMP.   North Oil : company
 WELL.   A-12 : well
 FLD .   Wildcat : field
 SRVC.   Gyro Services : service company
 UWI .   0012-345 : unique well id
 API .   42-501-20130 : api number
 LATI.   61 15 00.0 N : latitude
 LONG.   73 24 00.0 E : longitude
 DATE.   2024-05-01 : survey date
 LMF .   KB : log measured from
 EKB .F  82.0 : kelly bushing
 EGL .F  50.0 : ground level
 TOOL.   GWD: north seeking : tool type
 TOOLSN. SN-7 : serial number
"""


def test_well_metadata(tmp_path: Path) -> None:
    _, well = read(put(tmp_path, las(well=FULL_WELL)))
    assert well == WellMetadata(
        well="A-12",
        uwi="0012-345",
        field="Wildcat",
        company="North Oil",
        service_company="Gyro Services",
        latitude=61.25,
        longitude=73.4,
        elevation=82.0 * 0.3048,
        depth_reference="KB",
        survey_date=dt.date(2024, 5, 1),
        tool_type="GWD: north seeking",
        tool_serial="SN-7",
        north_reference="grid",
    )


def test_well_items_in_the_parameter_section(tmp_path: Path) -> None:
    parameters = " EKB .M  24.5 : kelly bushing\n LAT.DEG 61.5 : latitude\n"
    _, well = read(put(tmp_path, las(well=" WELL. A-1 : well\n", parameters=parameters)))
    assert (well.well, well.elevation, well.depth_reference, well.latitude) == (
        "A-1",
        24.5,
        "KB",
        61.5,
    )


def test_same_item_twice_with_different_values(tmp_path: Path) -> None:
    err = failure(put(tmp_path, las(well=" WELL. A-1 : well\n WELL. A-2 : well\n")))
    assert "WELL is given twice" in str(err)
    assert err.line == 7


@pytest.mark.parametrize(
    ("mnemonic", "value", "item_unit", "expected"),
    [
        ("LAT", "61.25", "", 61.25),
        ("LATI", "61.25", "DEG", 61.25),
        ("LATITUDE", "-61.25", "", -61.25),
        ("LAT", "61.25 S", "", -61.25),
        ("LAT", "S 61.25", "", -61.25),
        ("LAT", "61.25N", "", 61.25),
        ("LAT", "61 15 00 N", "", 61.25),
        ("LAT", "61°15'00\"N", "", 61.25),
        ("LAT", "61° 15.5' S", "", -(61 + 15.5 / 60)),
        ("LAT", "-61 15 36", "", -(61 + 15 / 60 + 36 / 3600)),
        ("LAT", "1.0690", "RAD", math.degrees(1.069)),
        ("LON", "73 24 00 W", "", -73.4),
        ("LONG", "73°24'E", "", 73.4),
        ("LONGITUDE", "1e-05", "deg", 1e-05),
    ],
)
def test_coordinates(
    tmp_path: Path, mnemonic: str, value: str, item_unit: str, expected: float
) -> None:
    _, well = read(put(tmp_path, las(well=f" {mnemonic}.{item_unit} {value} : coordinate\n")))
    found = well.latitude if mnemonic.startswith("LAT") else well.longitude
    assert found == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize(
    ("value", "item_unit", "message"),
    [
        ("61 75 00 N", "", "minutes and seconds"),
        ("61.5 15 N", "", "minutes and seconds"),
        ("-61.25 S", "", "both a sign and a hemisphere"),
        ("sixty one", "", "not a coordinate"),
        ("61 15 00 E", "", "not a coordinate"),
        ("61.25", "FT", "expected an angle"),
        ("95.0", "", "less than or equal to 90"),
    ],
)
def test_invalid_coordinates(tmp_path: Path, value: str, item_unit: str, message: str) -> None:
    text = las(well=f" LATI.{item_unit} {value} : latitude\n")
    err = failure(put(tmp_path, text))
    assert message in str(err)
    assert "LATI" in str(err)
    assert err.line == 6


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        ("2024-05-01", dt.date(2024, 5, 1)),
        ("2024/05/01", dt.date(2024, 5, 1)),
        ("20240501", dt.date(2024, 5, 1)),
        ("2024-05-01T13:45:00Z", dt.date(2024, 5, 1)),
        ("2024-05-01 13:45", dt.date(2024, 5, 1)),
        ("01-MAY-2024", dt.date(2024, 5, 1)),
        ("1 May 2024", dt.date(2024, 5, 1)),
        ("May 1, 2024", dt.date(2024, 5, 1)),
        ("SEPT 30 2024", dt.date(2024, 9, 30)),
        ("2024-MAY-01", dt.date(2024, 5, 1)),
        ("13-DEC-86", dt.date(1986, 12, 13)),
        ("13/05/2024", dt.date(2024, 5, 13)),
        ("05/13/2024", dt.date(2024, 5, 13)),
        ("05.05.2024", dt.date(2024, 5, 5)),
    ],
)
def test_dates(tmp_path: Path, value: str, expected: dt.date) -> None:
    _, well = read(put(tmp_path, las(well=f" DATE. {value} : survey date\n")))
    assert well.survey_date == expected


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("05/06/2024", "ambiguous: day 5 of month 6, or day 6 of month 5"),
        ("1/5/24", "ambiguous order"),
        ("yesterday", "not a date"),
        ("2024-02-30", "day is out of range"),
        ("31-Foo-2024", "'Foo' is not a month"),
        ("2024 05 01 extra", "not a date"),
        ("2026-11-99999999999999999999999999999", "too large to convert"),  # fuzz: OverflowError
        ("99999999999999999999 May 2024", "too large to convert"),
    ],
)
def test_invalid_dates(tmp_path: Path, value: str, message: str) -> None:
    err = failure(put(tmp_path, las(well=f" DATE. {value} : survey date\n")))
    assert message in str(err)
    assert "YYYY-MM-DD" in str(err)
    assert err.line == 6


@pytest.mark.parametrize(
    ("items", "elevation", "reference"),
    [
        (" EKB.M 24.5 : kb\n", 24.5, "KB"),
        (" EGL.F 100 : gl\n EKB.F 130 : kb\n LMF. GL : log measured from\n", 30.48, "GL"),
        (" EREF.M 10 : elevation\n DREF. RKB : depth reference\n", 10.0, "RKB"),
        (" EKB.M 1 : kb\n EDF.M 2 : df\n DMF. RDF : drilling measured from\n", 2.0, "RDF"),
        (" ELEV.M 5 : elevation\n", 5.0, None),
        (" LMF. DF : log measured from\n EKB.M 24 : kb\n", None, "DF"),
        (" EKB. 24.5 : kb\n", 24.5, "KB"),  # in the depths' unit (DEPT.M)
    ],
)
def test_elevation(
    tmp_path: Path, items: str, elevation: float | None, reference: str | None
) -> None:
    _, well = read(put(tmp_path, las(well=items)))
    assert well.elevation == (pytest.approx(elevation) if elevation is not None else None)
    assert well.depth_reference == reference


@pytest.mark.parametrize(
    ("items", "message"),
    [
        (" EKB.M 1 : kb\n EDF.M 2 : df\n", "no DREF, LMF or DMF"),
        (" STRT.F 0 :\n EKB. 24 : kb\n", "no unit, and the depths"),  # DEPT.M: which?
        (" EKB.DEG 24 : kb\n", "expected a length"),
        (" EKB.M high : kb\n", "'high' is not a number"),
    ],
)
def test_invalid_elevation(tmp_path: Path, items: str, message: str) -> None:
    assert message in str(failure(put(tmp_path, las(well=items))))


# ---------------------------------------------------------------------------- units


@pytest.mark.parametrize(
    ("md_unit", "factor"),
    [("F", 0.3048), ("FT", 0.3048), ("FEET", 0.3048), ("M", 1.0), ("m", 1.0), ("METRES", 1.0)],
)
@pytest.mark.parametrize(
    ("angle_unit", "angle_factor"),
    [("DEG", 1.0), ("DEGA", 1.0), ("°", 1.0), ("DEGREES", 1.0), ("RAD", 180 / math.pi)],
)
def test_station_unit_spellings(
    tmp_path: Path, md_unit: str, factor: float, angle_unit: str, angle_factor: float
) -> None:
    curves = f" DEPT.{md_unit} : depth\n INC.{angle_unit} : inc\n AZIM.{angle_unit} : azi TN\n"
    table, _ = read(put(tmp_path, las(curves, "0 0.5 1.5\n10 0.25 2.5\n")))
    assert column(table, "md") == [0.0, 10 * factor]
    assert column(table, "inc") == pytest.approx([0.5 * angle_factor, 0.25 * angle_factor])
    assert column(table, "azi") == pytest.approx([1.5 * angle_factor, 2.5 * angle_factor])
    assert north(table) == "true"


@pytest.mark.parametrize(
    ("dls_unit", "factor"),
    [
        ("DEG/100FT", 30 / 30.48),
        ("deg/100'", 30 / 30.48),
        ("°/100ft", 30 / 30.48),
        ("°/30m", 1.0),
        ("DEG/30M", 1.0),
    ],
)
def test_dogleg_unit_spellings(tmp_path: Path, dls_unit: str, factor: float) -> None:
    curves = STATION_CURVES + f" DLS.{dls_unit} : dogleg severity\n"
    table, _ = read(put(tmp_path, las(curves, "0 0 0 0\n100 1.5 45 2\n200 3 46.5 3\n")))
    assert column(table, "dls") == pytest.approx([0.0, 2 * factor, 3 * factor], rel=1e-15)
    assert unit(table, "dls") == "deg/30m"


@pytest.mark.parametrize(
    ("column_name", "mnemonic", "spelling", "factor"),
    [
        ("time", "TIME", "S", 1.0),
        ("time", "TIME", "SEC", 1.0),
        ("time", "TIME", "MIN", 60.0),
        ("gyro_x", "WX", "DEG/HR", 1.0),
        ("gyro_x", "WX", "deg/h", 1.0),
        ("gyro_x", "WX", "°/h", 1.0),
        ("gyro_x", "WX", "DEG/S", 3600.0),
        ("gyro_x", "WX", "RAD/S", 180 / math.pi * 3600),
        ("acc_x", "GX", "M/S2", 1.0),
        ("acc_x", "GX", "m/s²", 1.0),
        ("acc_x", "GX", "G", 9.80665),
        ("mag_x", "BX", "NT", 1.0),
        ("mag_x", "BX", "UT", 1000.0),
        ("mag_x", "BX", "µT", 1000.0),
        ("mag_x", "BX", "μT", 1000.0),
        ("mag_x", "BX", "GAUSS", 1e5),
    ],
)
def test_sample_unit_spellings(
    tmp_path: Path, column_name: str, mnemonic: str, spelling: str, factor: float
) -> None:
    units = SAMPLE_UNITS | {"BX": "NT"} | {mnemonic: spelling}
    curves = "".join(f" {m}.{u} : {m.lower()}\n" for m, u in units.items())
    table, _ = read(
        put(tmp_path, las(curves, "0.00 0.1 0.2 9.8 5 3\n0.01 0.1 0.2 9.8 6 3\n")), "samples"
    )
    raw = {"time": 0.01, "gyro_x": 6.0, "acc_x": 0.1, "mag_x": 3.0}[column_name]
    assert column(table, column_name)[1] == pytest.approx(raw * factor, rel=1e-15)


def test_feet_converted_exactly(tmp_path: Path) -> None:
    curves = (
        " DEPT.FT : md\n INC.DEG : inc\n AZI.DEG : azi\n TVD.FT : tvd\n NS.FT : ns\n EW.F : ew\n"
    )
    data = "0 0 0 0 0 0\n100.5 1 2 100.4 1.5 -2.25\n"
    table, _ = read(put(tmp_path, las(curves, data)), north_reference="true")
    assert column(table, "md") == [0.0, 100.5 * 0.3048]
    assert column(table, "tvd") == [0.0, 100.4 * 0.3048]
    assert column(table, "north") == [0.0, 1.5 * 0.3048]
    assert column(table, "east") == [0.0, -2.25 * 0.3048]


def test_units_option_overrides_the_file(tmp_path: Path) -> None:
    curves = " DEPT.FURLONG : depth\n INC. : inc\n AZI.DEG : azi GN\n"
    table, _ = read(put(tmp_path, las(curves)), units={"md": "ft", "inc": "rad"})
    assert column(table, "md") == [0.0, 100 * 0.3048, 200 * 0.3048]
    assert column(table, "inc")[1] == pytest.approx(math.degrees(1.5))


@pytest.mark.parametrize(
    ("curve", "message"),
    [
        (" DEPT.FURLONG : depth\n", "unknown unit 'FURLONG', expected a length"),
        (" DEPT. : depth\n", "has no unit"),
        (" DEPT.DEG : depth\n", "is an angle, expected a length"),
    ],
)
def test_needed_curve_without_a_known_unit(tmp_path: Path, curve: str, message: str) -> None:
    text = las(curve + STATION_CURVES.split("\n", 1)[1])
    err = failure(put(tmp_path, text))
    assert message in str(err)
    assert "option units" in str(err)
    assert "units: {md: m}" in str(err)
    assert (err.column, err.line) == ("DEPT", text.splitlines().index(curve.rstrip()) + 1)


def test_unit_of_an_ignored_curve_does_not_matter(tmp_path: Path) -> None:
    table, _ = read(put(tmp_path, las(STATION_CURVES + " GR.FURLONG : gamma\n", "0 0 0 1\n")))
    assert table.num_rows == 1


# ------------------------------------------------------------------------- layouts

LAS12 = """\
~VERSION INFORMATION
 VERS.                  1.2:   CWLS LOG ASCII STANDARD -VERSION 1.2
 WRAP.                  NO:   ONE LINE PER DEPTH STEP
~WELL INFORMATION BLOCK
#MNEM.UNIT       DATA TYPE    INFORMATION
#---------    -------------   ------------------------------
 STRT.M        1670.0000:
 STOP.M        1670.2500:
 STEP.M        0.1250:
 NULL.         -999.2500:
 COMP.             COMPANY:   ANY OIL COMPANY INC.
 WELL.                WELL:   AAAAA_2
 FLD .               FIELD:   WILDCAT
 LOC .            LOCATION:   12-34-12-34W5M
 DATE.            LOG DATE:   13-DEC-1986
 UWI .      UNIQUE WELL ID:   100123401234W500
~CURVE INFORMATION BLOCK
#MNEM.UNIT      API CODE     CURVE DESCRIPTION
#---------    -------------   ------------------------------
 DEPT.M                       :  1  DEPTH
 DEVI.DEG                     :  2  DEVIATION
 HAZI.DEG                     :  3  AZIMUTH TRUE NORTH
 GR  .GAPI   45 310 01 00     :  4  GAMMA RAY
~A  DEPTH     DEVI     HAZI     GR
 1670.000   1.2500   123.450  -999.2500
 1670.125   1.3750   124.000    68.500
 1670.250   1.5000   125.125    70.250
"""


def test_las_1_2_layout(tmp_path: Path) -> None:
    table, well = read(put(tmp_path, LAS12))
    assert column(table, "md") == [1670.0, 1670.125, 1670.25]
    assert column(table, "inc") == [1.25, 1.375, 1.5]
    assert column(table, "azi") == [123.45, 124.0, 125.125]
    assert column(table, "source_line") == [25, 26, 27]
    assert north(table) == "true"
    assert (well.well, well.company, well.field, well.uwi) == (
        "AAAAA_2",
        "ANY OIL COMPANY INC.",
        "WILDCAT",
        "100123401234W500",
    )
    assert well.survey_date == dt.date(1986, 12, 13)


WRAPPED = """\
~VERSION INFORMATION
 VERS.                 2.0 : CWLS log ASCII Standard -VERSION 2.0
 WRAP.                 YES : Multiple lines per depth step
~WELL INFORMATION
 STRT.M                910.000 :
 STOP.M                910.250 :
 STEP.M                0.125 :
 NULL.                 -999.25 :
~CURVE INFORMATION
 DEPT.M                :  Depth
 INC .DEG              :  Inclination
 AZI .DEG              :  Azimuth (magnetic)
 GR  .GAPI             :  Gamma ray
 SP  .MV               :  SP
 RHOB.K/M3             :  Density
~A
910.000
 1.2500  123.450
 -999.25 -30.0 2550.000
910.125
 1.3750  124.000  68.500
 -31.0 2551.000
910.250
 1.5000  125.125  70.250  -32.0
 2552.000
"""


def test_wrapped_file(tmp_path: Path) -> None:
    path = put(tmp_path, WRAPPED)
    table, _ = read(path)
    assert column(table, "md") == [910.0, 910.125, 910.25]
    assert column(table, "inc") == [1.25, 1.375, 1.5]
    assert column(table, "azi") == [123.45, 124.0, 125.125]
    assert column(table, "source_line") == [17, 20, 23]
    assert north(table) == "magnetic"
    reference = lasio.read(str(path))
    for name, i in (("md", 0), ("inc", 1), ("azi", 2)):
        assert np.array_equal(as_nan(table, name), reference.curves[i].data)


@pytest.mark.parametrize(
    ("data", "line", "message"),
    [
        ("910.0 1.25\n", 17, "index value alone"),
        ("910.0\n1 2 3 4 5 6\n", 18, "has 7 values here"),
        ("910.0\n1 2 3\n910.1\n1 2 3\n", 20, "has 8 values here"),
        ("910.0\n1 2 3 4 5\n910.1\n1 2\n", 19, "last row has 3 of 6"),
    ],
)
def test_broken_wrapped_rows(tmp_path: Path, data: str, line: int, message: str) -> None:
    text = WRAPPED.split("~A\n")[0].replace(" STRT.M", " XSTRT.M").replace(" STOP.M", " XSTOP.M")
    err = failure(put(tmp_path, text + "~A\n" + data))
    assert message in str(err)
    assert err.line == line


LAS3 = """\
~Version
VERS.   3.0 : CWLS LOG ASCII STANDARD - VERSION 3.0
WRAP.   NO  : ONE LINE PER DEPTH STEP
DLM .   COMMA : DELIMITING CHARACTER
~Well
STRT .M 1500.0 : First Index Value
STOP .M 1500.2 : Last Index Value
STEP .M 0.1 : STEP
NULL . -999.25 : NULL VALUE
WELL . A-1 : WELL
~Log_Parameter
BHT .DEGC 35.5 : Bottom Hole Temperature
~Log_Definition
DEPT .M : Depth {F}
INC .DEG : Inclination {F}
AZI .DEG : Azimuth true north {F}
REMARK . : Remark {S}
~Log_Data | Log_Definition
1500.0, 1.0, 10.0, "fine"
1500.1, 2.0, -999.25, "a b"
1500.2, 3.0, 30.0, "c"
~Tops_Definition
TOPT. : Top Name {S}
~Tops_Data | Tops_Definition
Top1
"""


def test_las_3_single_log(tmp_path: Path) -> None:
    table, well = read(put(tmp_path, LAS3))
    assert column(table, "md") == [1500.0, 1500.1, 1500.2]
    # a null azimuth is an undefined one: NaN (the contract allows it only at vertical)
    np.testing.assert_array_equal(as_nan(table, "azi"), [10.0, np.nan, 30.0])
    assert column(table, "source_line") == [19, 20, 21]
    assert north(table) == "true"
    assert well.well == "A-1"


def test_line_ends_and_tabs(tmp_path: Path) -> None:
    text = las(data="0\t0\t0\n100  1.5\t 45  \n200 3 46.5\n")
    expected, _ = read(put(tmp_path, text))
    for variant in (text.replace("\n", "\r\n"), text.replace("\n", "\r")):
        table, _ = read(put(tmp_path, variant, "variant.las"))
        assert table.equals(expected)


def test_comment_and_blank_lines_in_the_data(tmp_path: Path) -> None:
    text = las(data="0 0 0\n\n# a comment\n100 1.5 45\n   \n200 3 46.5\n\x1a")
    table, _ = read(put(tmp_path, text))
    first = data_line(text)
    assert column(table, "md") == [0.0, 100.0, 200.0]
    assert column(table, "source_line") == [first, first + 3, first + 5]


# --------------------------------------------------------------------------- nulls


@pytest.mark.parametrize(
    ("null", "data", "nulls"),
    [
        ("-999.25", "0 0 -999.25\n100 -999.2500 45\n200 -9.9925E+02 46.5\n", 3),
        ("-9999", "0 0 -9999\n100 -9999.0 45\n200 3 -999.25\n", 3),  # -999.25: always
        ("9999.99", "0 0 9999.99\n100 1.5 45\n200 3 46.5\n", 1),
        ("-999.25", "0 0 2147483647\n100 1.5 9999.99\n200 3 -9999\n", 0),
    ],
)
def test_declared_nulls(tmp_path: Path, null: str, data: str, nulls: int) -> None:
    path = put(tmp_path, las(data=data, null=null))
    table, _ = read(path)
    undefined = int(np.isnan(as_nan(table, "azi")).sum())  # a null azimuth reads as NaN
    assert table.column("inc").null_count + undefined == nulls
    reference = lasio.read(str(path))
    for name, i in (("md", 0), ("inc", 1), ("azi", 2)):
        expected = reference.curves[i].data.copy()
        if name != "md":  # lasio keeps -999.25 under another NULL: a null in every gyropipe reader
            expected[np.isin(expected, NULL_MARKERS)] = np.nan
        assert np.array_equal(as_nan(table, name), expected, equal_nan=True)


def test_other_null_declarations(tmp_path: Path) -> None:
    text = las(data="0 0 0\n100 1.5 -9999\n200 77 46.5\n", parameters=" NULL. -9999 : also\n")
    table, _ = read(put(tmp_path, text), null_values=[77])
    np.testing.assert_array_equal(as_nan(table, "azi"), [0.0, np.nan, 46.5])
    assert column(table, "inc") == [0.0, 1.5, None]


def test_null_index(tmp_path: Path) -> None:
    text = las(data="0 0 0\n-999.25 1.5 45\n")
    err = failure(put(tmp_path, text))
    assert "null value -999.25 in curve DEPT: every row needs its index value" in str(err)
    assert (err.column, err.line) == ("DEPT", data_line(text) + 1)


def test_null_time_in_samples(tmp_path: Path) -> None:
    text = las(" DEPT.M : d\n" + SAMPLE_CURVES, "0 -999.25 0 0 0 0\n")
    err = failure(put(tmp_path, text), "samples")
    assert (err.column, err.line) == ("TIME", data_line(text))


# ----------------------------------------------------------------------- encodings


def test_non_ascii_units_in_utf8_and_windows_1252(tmp_path: Path) -> None:
    curves = " DEPT.m : Tiefe\n INC.° : Neigung\n AZI.° : Azimut (true north)\n DLS.°/30m : Knick\n"
    text = las(curves, "0 0 0 0\n100 1.5 45 2.5\n", well=" FLD. Südfeld µ : field\n")
    tables = []
    for name, content in (
        ("utf8.las", text.encode()),
        ("bom.las", b"\xef\xbb\xbf" + text.encode()),
        ("cp1252.las", text.encode("cp1252")),
    ):
        table, well = read(put(tmp_path, content, name))
        assert well.field == "Südfeld µ"
        tables.append(table)
    assert tables[0].equals(tables[1])
    assert tables[0].equals(tables[2])
    assert column(tables[0], "dls") == [0.0, 2.5]


def test_micro_sign_unit_in_windows_1252(tmp_path: Path) -> None:
    text = las(SAMPLE_CURVES + " BZ.µT : mag z\n", "0 0 0 9.8 5 50\n")
    table, _ = read(put(tmp_path, text.encode("cp1252")), "samples")
    assert column(table, "mag_z") == [50000.0]


@pytest.mark.parametrize(
    ("content", "line", "message"),
    [
        (las(well=" WELL. A\x81B : well\n").encode("latin-1"), 6, "byte 0x81"),
        (las(data="0 0 0\n1\x00 2 3\n").encode(), 12, "NUL byte"),
        (las().encode().replace(b"inclination", b"incl\x00"), 8, "NUL byte"),
        (las(data="0 0 0\n100 1.5 \x8145\n").encode("latin-1"), 12, "byte 0x81"),
    ],
)
def test_bad_encoding(tmp_path: Path, content: bytes, line: int, message: str) -> None:
    err = failure(put(tmp_path, content))
    assert message in str(err)
    assert err.line == line


# ------------------------------------------------------------------ station listing

LISTING = """\
~Version
 VERS.  2.0 : CWLS
 WRAP.  NO : one line per station
~Well
 STRT.FT      0.00 : start
 STOP.FT   2000.00 : stop
 STEP.FT      0.00 : irregular
 NULL.     -999.25 : null
 WELL.     Ridge 3H : well
 NREF.     GRID : north reference
~Curve
 MD   .FT        : measured depth
 INC  .DEG       : inclination
 AZI  .DEG       : azimuth
 TVD  .FT        : true vertical depth
 +N/-S.FT        : north
 +E/-W.FT        : east
 DLS  .DEG/100FT : dogleg severity
~A
      0.00    0.00    0.00       0.00      0.00      0.00    0.00
    500.00    1.50   45.00     499.94      4.63      4.63    0.30
   1000.00    3.00   46.50     999.60     18.43     19.02    0.30
   2000.00    3.00   46.50    1998.23     54.52     57.09    0.00
"""


def test_station_listing(tmp_path: Path) -> None:
    table, well = read(put(tmp_path, LISTING))
    names = ["md", "inc", "azi", "tvd", "north", "east", "dls", "source_line"]
    assert table.column_names == names
    assert column(table, "md") == [0.0, 500 * 0.3048, 1000 * 0.3048, 2000 * 0.3048]
    assert column(table, "tvd")[3] == 1998.23 * 0.3048
    assert column(table, "north")[2] == 18.43 * 0.3048
    assert column(table, "east")[3] == 57.09 * 0.3048
    assert column(table, "dls")[1] == pytest.approx(0.3 * 30 / 30.48, rel=1e-15)
    assert [unit(table, n) for n in ("tvd", "north", "east", "dls")] == ["m", "m", "m", "deg/30m"]
    assert north(table) == "grid"
    assert well.north_reference == "grid"
    Stations.validate_table(table)


# ---------------------------------------------------------------------- raw samples

RAW = """\
~Version
 VERS.  2.0 : CWLS
 WRAP.  NO : one line per sample
~Well
 STRT.S  0.00 : start
 STOP.S  0.02 : stop
 STEP.S  0.01 : step
 NULL.   -999.25 : null
~Curve
 TIME .S      : elapsed time
 DEPT .M      : depth
 GX   .M/S2   : accelerometer x
 GY   .M/S2   : accelerometer y
 GZ   .M/S2   : accelerometer z
 WX   .DEG/HR : gyro x
 BX   .NT     : magnetometer x
 BY   .NT     : magnetometer y
 BZ   .NT     : magnetometer z
 TEMP .DEGC   : temperature
~A
 0.00  1000.0  0.10  -0.20  -9.80   5.0  11000.0  3500.0  -58000.0  40.1
 0.01  1000.0  0.11  -0.21  -9.81   5.5  11001.0  3501.0  -58001.0  40.1
 0.02  1000.1  0.12  -0.22  -9.82   6.0  11002.0  3502.0  -58002.0  40.2
"""


def test_raw_sensor_log_as_samples(tmp_path: Path) -> None:
    table, _ = read(put(tmp_path, RAW), "samples")
    assert table.column_names == [
        "time",
        "md",
        "gyro_x",
        "acc_x",
        "acc_y",
        "acc_z",
        "mag_x",
        "mag_y",
        "mag_z",
        "source_line",
    ]
    assert column(table, "time") == [0.0, 0.01, 0.02]
    assert column(table, "acc_z") == [-9.8, -9.81, -9.82]
    assert [unit(table, n) for n in ("time", "gyro_x", "acc_x", "mag_x")] == [
        "s",
        "deg/h",
        "m/s2",
        "nT",
    ]
    RawSamples.validate_table(table)


def test_conventions_are_applied_to_samples(tmp_path: Path) -> None:
    conventions = {
        "accelerometer": "specific_force",
        "gyro_rotation": "left_hand",
        "axes": ["x", "y", "-z"],
    }
    table, _ = read(put(tmp_path, RAW), "samples", conventions=conventions)
    assert column(table, "acc_x") == [-0.10, -0.11, -0.12]
    assert column(table, "acc_z") == [-9.8, -9.81, -9.82]  # −(−1·z): both flips
    assert column(table, "gyro_x") == [-5.0, -5.5, -6.0]
    assert column(table, "mag_x") == [11000.0, 11001.0, 11002.0]
    assert column(table, "mag_z") == [58000.0, 58001.0, 58002.0]
    assert unit(table, "acc_x") == "m/s2"


def test_conventions_needing_a_missing_axis(tmp_path: Path) -> None:
    err = failure(put(tmp_path, RAW), "samples", conventions={"axes": ["y", "x", "z"]})
    assert "option conventions" in str(err)
    assert "gyro" in str(err)


def test_depth_log_is_not_samples(tmp_path: Path) -> None:
    path = put(tmp_path, las())
    err = failure(path, "samples")
    assert isinstance(err, WrongKindError)
    assert str(err) == (
        f"{path}: a depth-indexed LAS log with curves INCL, AZIM; not raw sensor samples "
        "(needs TIME, WX, GX, GY, GZ)"
    )


def test_samples_missing_one_curve_name_the_accepted_mnemonics(tmp_path: Path) -> None:
    err = failure(put(tmp_path, RAW.replace(" GY   .M/S2", " QQ   .M/S2")), "samples")
    assert isinstance(err, WrongKindError)
    assert "no curve for acc_y" in str(err)
    assert "GY, ACCY, ACCELY" in str(err)


def test_integer_columns(tmp_path: Path) -> None:
    curves = SAMPLE_CURVES + " STN. : station\n POS. : position\n"
    data = "0 0 0 9.8 5 0 -999.25\n0.01 0 0 9.8 5 1.0 2\n"
    table, _ = read(put(tmp_path, las(curves, data)), "samples")
    assert table.schema.field("station").type == pa.int64()
    assert column(table, "station") == [0, 1]
    assert column(table, "position") == [None, 2]
    err = failure(put(tmp_path, las(curves, "0 0 0 9.8 5 0.5 1\n")), "samples")
    assert (err.column, "whole number" in str(err)) == ("STN", True)


def test_numeric_survey_ids_become_text(tmp_path: Path) -> None:
    curves = STATION_CURVES + " SURVEY. : survey id\n"
    table, _ = read(put(tmp_path, las(curves, "0 0 0 1\n100 1 2 1.5\n200 2 3 -999.25\n")))
    assert column(table, "survey") == ["1", "1.5", None]


# ------------------------------------------------------------------ curve choice


def test_columns_option(tmp_path: Path) -> None:
    curves = " DEPTH.M : d\n MD.M : other depth\n DIP.DEG : inc\n DIR.DEG : azimuth (true)\n"
    path = put(tmp_path, las(curves, "0 5 1 2\n1 6 3 4\n"))
    err = failure(path)
    assert "several curves look like md: DEPTH, MD" in str(err)
    table, _ = read(path, columns={"md": "md", "inc": "DIP", "azi": "dir"})
    assert column(table, "md") == [5.0, 6.0]
    assert column(table, "inc") == [1.0, 3.0]
    assert north(table) == "true"
    err = failure(path, columns={"md": "DEPTHS", "inc": "DIP", "azi": "DIR"})
    assert "option columns: md: 'DEPTHS' names no curve" in str(err)
    err = failure(path, columns={"toolface": "DIR"})
    assert "option columns: toolface is not read here (read: survey, md, inc" in str(err)


@pytest.mark.parametrize(
    ("mnemonic", "ref"),
    [("AZTN", "true"), ("AZGN", "grid"), ("AZI_MN", "magnetic"), ("Azimuth_TN", "true")],
)
def test_north_reference_in_the_mnemonic(tmp_path: Path, mnemonic: str, ref: str) -> None:
    curves = f" DEPT.M : d\n INC.DEG : i\n {mnemonic}.DEG : a\n"
    table, well = read(put(tmp_path, las(curves)))
    assert north(table) == ref
    assert well.north_reference == ref


def test_azimuth_chosen_by_north_reference(tmp_path: Path) -> None:
    curves = " DEPT.M : d\n INC.DEG : i\n AZTN.DEG : a\n AZGN.DEG : a\n"
    path = put(tmp_path, las(curves, "0 0 10 11\n"))
    assert "several curves look like azi: AZTN, AZGN" in str(failure(path))
    table, well = read(path, north_reference="grid")
    assert column(table, "azi") == [11.0]
    assert (north(table), well.north_reference) == ("grid", "grid")


@pytest.mark.parametrize(
    ("azimuth", "well", "options", "message"),
    [
        ("AZTN.DEG : azimuth", " NREF. GRID : ref\n", {}, "true (curve AZTN on line"),
        ("AZI.DEG : grid azimuth", "", {"north_reference": "magnetic"}, "magnetic (option"),
        ("AZI.DEG : true and magnetic", "", {}, "conflicting"),
    ],
)
def test_conflicting_north_references(
    tmp_path: Path, azimuth: str, well: str, options: dict[str, Any], message: str
) -> None:
    text = las(f" DEPT.M : d\n INC.DEG : i\n {azimuth}\n", well=well)
    err = failure(put(tmp_path, text), **options)
    assert "conflicting north references" in str(err)
    assert message in str(err)


def test_no_north_reference(tmp_path: Path) -> None:
    path = put(tmp_path, las(" DEPT.M : d\n INC.DEG : i\n AZI.DEG : azimuth\n"))
    err = failure(path)
    assert "no north reference" in str(err)
    assert "NREF" in str(err)
    table, well = read(path, default_north_reference="magnetic")
    assert (north(table), well.north_reference) == ("magnetic", None)
    table, well = read(path, north_reference="grid", default_north_reference="magnetic")
    assert (north(table), well.north_reference) == ("grid", None)


def test_bad_nref_value(tmp_path: Path) -> None:
    err = failure(put(tmp_path, las(well=" NREF. sideways : ref\n")))
    assert "NREF 'sideways': expected true, grid or magnetic" in str(err)


# --------------------------------------------------------------------- bad files


def test_truncated_mid_row(tmp_path: Path) -> None:
    text = las(data="0 0 0\n100 1.5 45\n200 3")
    err = failure(put(tmp_path, text))
    assert "expected 3 values (one per curve: DEPT, INCL, AZIM), got 2" in str(err)
    assert err.line == data_line(text) + 2


def test_truncated_at_a_row_end(tmp_path: Path) -> None:
    well = " STRT.M 0 : start\n STOP.M 300.0 : stop\n STEP.M 100 : step\n"
    text = las(data=STATION_DATA, well=well)
    err = failure(put(tmp_path, text))
    assert "STOP is 300 but the last index value (DEPT) is 200" in str(err)
    assert "truncated" in str(err)
    assert err.line == data_line(text) + 2


def test_lost_row(tmp_path: Path) -> None:
    well = " STRT.M 0 : start\n STOP.M 300 : stop\n STEP.M 100 : step\n"
    text = las(data="0 0 0\n100 1.5 45\n300 3 46.5\n", well=well)
    err = failure(put(tmp_path, text))
    assert "STEP is 100 but the index steps by 200" in str(err)
    assert err.line == data_line(text) + 2


@pytest.mark.parametrize("threads", [1, 2], ids=["one thread", "read ahead"])
def test_a_row_lost_at_or_between_block_borders_is_found(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, threads: int
) -> None:
    """STEP is checked across the fast path's blocks (three rows each here): a row lost
    anywhere, next to a block's first or last row or within one, is reported at the row
    after the gap."""
    monkeypatch.setattr(las_fast, "BLOCK", 64)
    monkeypatch.setattr(io_threads, "reader_threads", lambda: threads)
    rows = [f"{10.0 * i:8.1f}{1.5:6.2f}{45.0:7.1f}" for i in range(30)]
    well = " STRT.M 0 : start\n STOP.M 290 : stop\n STEP.M 10 : step\n"
    assert read(put(tmp_path, las(data="\n".join(rows) + "\n", well=well)))[0].num_rows == 30
    for lost in range(1, 29):
        text = las(data="\n".join(rows[:lost] + rows[lost + 1 :]) + "\n", well=well)
        err = failure(put(tmp_path, text))
        assert "STEP is 10 but the index steps by 20" in str(err)
        assert err.line == data_line(text) + lost


def test_index_range_in_other_units_and_rounded(tmp_path: Path) -> None:
    well = " STRT.FT 0.0 : start\n STOP.FT 656.2 : stop\n STEP.FT 328.1 : step\n"
    table, _ = read(put(tmp_path, las(data=STATION_DATA, well=well)))
    assert table.num_rows == 3
    text = las(data=STATION_DATA, well=well.replace("0.0 :", "1.0 :"))
    assert "STRT is 0.3048 but the first index value" in str(failure(put(tmp_path, text)))


@pytest.mark.parametrize(
    ("data", "row", "message", "curve"),
    [
        ("0 0 0\n100 1.5 45 7\n", 1, "expected 3 values", ""),
        ("0 0\n", 0, "got 2", ""),
        ("0 0 0\n100 abc 45\n", 1, "expected a number, got 'abc'", "INCL"),
        ("0 0 0\n100 1.5 4-5\n", 1, "expected a number, got '4-5'", "AZIM"),
        ("0 0 0\n100 1,5 45\n", 1, "expected a number, got '1,5'", "INCL"),
        ("0 0 0\n100 1.5 nan\n", 1, "expected a number, got 'nan'", "AZIM"),
        ("0 0 0\n100 1e999 45\n", 1, "'1e999' is out of range", "INCL"),
        ("0 0 0\n~A\n100 1.5 45\n", 1, "a second data section", ""),
        ("0 0 0\n~Other\nnote\n", 1, "after the ~A section", ""),
    ],
)
def test_bad_data(tmp_path: Path, data: str, row: int, message: str, curve: str) -> None:
    text = las(data=data)
    err = failure(put(tmp_path, text))
    assert message in str(err)
    assert (err.line, err.column) == (data_line(text) + row, curve)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "the file is empty"),
        ("  \n\n", "the file is empty"),
        (las().split("~A")[0], "no ~A (data) section"),
        (las(data=""), "no data rows"),
        (las(data="\n\n"), "no data rows"),
        (las(curves=""), "no curves"),
        (las().replace(" VERS. 2.0", " VERS. two"), "VERS 'TWO': not a LAS version"),
        (las().replace(" VERS. 2.0", " VERS. 4.0"), "not a LAS version"),
        (las().replace(" WRAP. NO", " WRAP. MAYBE"), "WRAP 'MAYBE'"),
        (las().replace("~Curve\n", "~Curve\n this is not an item\n"), "cannot read header line"),
        (las(STATION_CURVES.replace("INCL", "FOO")), "no curve for inc"),
        (las(null="none"), "NULL 'none' is not a number"),
    ],
)
def test_bad_files(tmp_path: Path, content: str, message: str) -> None:
    assert message in str(failure(put(tmp_path, content)))


def test_missing_file(tmp_path: Path) -> None:
    assert "cannot read the file" in str(failure(tmp_path / "missing.las"))


# ------------------------------------------------ fast path, careful path and lasio

_value = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False, width=64),
    st.floats(-1e6, 1e6, allow_nan=False).map(lambda v: round(v, 3)),
    st.integers(-(10**6), 10**6).map(float),
)
_format = st.sampled_from(["{!r}", "{:.3f}", "{:.6e}", "{:+.12g}", "{:12.4f}", "{:E}"])
_gap = st.sampled_from([" ", "  ", "\t", " \t ", "      "])


@st.composite
def data_sections(draw: st.DrawFn) -> tuple[str, int]:
    """A ~A section of random numbers in random layouts, and its curve count."""
    n = draw(st.integers(1, 5))
    rows = draw(st.lists(st.lists(_value, min_size=n, max_size=n), min_size=2, max_size=12))
    fmt = draw(_format)
    lines = []
    for row in rows:
        cells = [fmt.format(v) for v in row]
        gaps = [draw(_gap) for _ in cells]
        lead, tail = draw(st.sampled_from(["", " ", "   "])), draw(st.sampled_from(["", " "]))
        lines.append(lead + "".join(g + c for g, c in zip(gaps, cells, strict=True))[1:] + tail)
    end = draw(st.sampled_from(["\n", "\r\n"]))
    return end.join(lines) + draw(st.sampled_from(["", end, end + end])), n


def _both_paths(path: Path) -> tuple[dict[int, np.ndarray] | None, las_rows.Data]:
    """Values of every curve by the fast path (None if it declines) and the careful path."""
    source = las_header.load(path)
    header = las_header.parse_header(path, source.header)
    wanted = list(range(len(header.curves)))
    blocks = las_fast.fast_values(source.raw, source.start, len(header.curves), wanted)
    lines = las_header.split_lines(source.raw[source.start :].decode())
    slow = las_rows._slow_values(path, header, lines, source.title_line, wanted)
    if blocks is None:
        return None, slow
    return {i: np.concatenate([b.values[i] for b in blocks] or [[]]) for i in wanted}, slow


@settings(
    max_examples=120,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(section=data_sections())
def test_fast_path_equals_careful_path_and_lasio(tmp_path: Path, section: tuple[str, int]) -> None:
    data, n = section
    curves = "".join(f" C{i}.M : curve {i}\n" for i in range(n))
    text = las(curves, data, null="-1.5e300")
    path = put(tmp_path, text)
    fast, slow = _both_paths(path)
    assert fast is not None  # the fast path reads every such layout
    for i, values in slow.values.items():
        assert np.array_equal(fast[i].view(np.int64), values.view(np.int64))
    first = data_line(text)
    assert list(slow.lines) == list(range(first, first + len(slow.lines)))
    reference = lasio.read(str(path))
    for i in range(n):
        expected = np.asarray(reference.curves[i].data, dtype=float).reshape(-1)
        assert np.array_equal(expected.view(np.int64), fast[i].view(np.int64))


@pytest.mark.parametrize(
    "data",
    [
        b"0 0 0\n\n100 1.5 45\n",
        b"# comment\n0 0 0\n100 1.5 45\n",
        b"0 0 0\r100 1.5 45\r\n",
        b"0 0 0\n100 1.5 45\x0c\n",
        b"0 0 0\n100 1.5 1e999\n",
        b"0 0 0\n100 1.5 45 x\n",
        b"0 0 0\n100 1.5 4-5\n",
        b"0 0 0\n100 1.5\n",
    ],
)
def test_fast_path_declines_what_it_cannot_prove(data: bytes) -> None:
    head = b"~Curve\n D.M : d\n~A\n"
    assert las_fast.fast_values(head + data, len(head), 3, [0, 1, 2]) is None


# ------------------------------------------------------------------------- writer

WELL = WellMetadata(
    well="A-12",
    uwi="0012-345",
    field="Wildcat",
    company="North Oil",
    service_company="Gyro Services",
    latitude=61.25,
    longitude=-73.4,
    elevation=24.9936,
    depth_reference="RKB",
    survey_date=dt.date(2024, 5, 1),
    tool_type="GWD: north-seeking",
    tool_serial="SN=7",
    north_reference="grid",
)


def _stations(columns: dict[str, list[Any]], ref: str | None = "grid") -> pa.Table:
    return Stations.compiled().make_table(columns, north_reference=ref)


def test_writer_format(tmp_path: Path) -> None:
    table = _stations({"survey": ["S1", "S1"], "md": [0.0, 0.1], "inc": [0.0, 1 / 3]})
    table = table.append_column(
        pa.field("azi", pa.float64(), metadata={UNIT_KEY: b"deg", NORTH_KEY: b"grid"}),
        pa.array([359.5, None]),
    )
    path = tmp_path / "out.las"
    WRITER.write(table, path, WellMetadata(well="A-1", survey_date=dt.date(2024, 5, 1)))
    lines = [" ".join(line.split()) for line in path.read_text().splitlines()]
    assert lines[:8] == [
        "~Version Information",
        "VERS . 2.0 : CWLS log ASCII Standard - version 2.0",
        "WRAP . NO : one line per index step",
        "~Well Information",
        "STRT .m 0.0 : first index value",
        "STOP .m 0.1 : last index value",
        "STEP .m 0.1 : index step, 0 if irregular",
        "NULL . -999.25 : null value",
    ]
    assert "WELL . A-1 : well" in lines
    assert "DATE . 2024-05-01 : survey date" in lines
    assert "UWI . : unique well identifier" in lines
    assert "NREF . grid : north reference of the azimuths" in lines
    assert "azi .deg : azimuth clockwise from north (grid north)" in lines
    assert "Columns not written: survey (string)" in lines
    assert lines[-3:] == ["~ASCII md inc azi", "0 0 359.5", "0.1 0.333333 -999.25"]
    assert lasio.read(str(path)).well["WELL"].value == "A-1"


@pytest.mark.parametrize(
    ("columns", "index"),
    [
        (["time", "md", "inc", "azi"], "md"),
        (["md", "time", "gyro_x"], "time"),
        (["gyro_x", "md"], "md"),
        (["gyro_x", "acc_x"], "gyro_x"),
    ],
)
def test_writer_index_column(tmp_path: Path, columns: list[str], index: str) -> None:
    table = pa.table({name: [1.0, 2.0] for name in columns})
    path = tmp_path / "out.las"
    WRITER.write(table, path, WellMetadata())
    ascii_title = next(line for line in path.read_text().splitlines() if line.startswith("~A"))
    assert ascii_title.split()[1] == index


@pytest.mark.parametrize(("name", "value"), [("inc", -999.25), ("azi", 999.25), ("tvd", -9999.25)])
def test_writer_refuses_values_every_reader_takes_for_nulls(
    tmp_path: Path, name: str, value: float
) -> None:
    columns = {"md": [0.0, 1.0, 2.0], "inc": [0.0, None, 1.0], "azi": [0.0, 1.0, 2.0]}
    table = _stations({**columns, name: [0.0, value, 1.0]} if name != "tvd" else columns)
    if name == "tvd":
        tvd = pa.array([0.0, value, 1.0])
        table = table.append_column(pa.field("tvd", pa.float64(), metadata={UNIT_KEY: b"m"}), tvd)
    with pytest.raises(ValueError, match=f"column '{name}' holds a null marker"):
        WRITER.write(table, tmp_path / "out.las", WELL)


def test_writer_keeps_a_depth_of_999_25(tmp_path: Path) -> None:
    table = _stations({"md": [0.0, 999.25, 9999.25], "inc": [0.0, None, 1.0], "azi": [0, 1, 2]})
    WRITER.write(table, tmp_path / "out.las", WELL)
    assert (
        " NULL    .         -999.25                  : null value"
        in (tmp_path / "out.las").read_text()
    )
    back, _ = read(tmp_path / "out.las")
    assert column(back, "md") == [0.0, 999.25, 9999.25]
    assert column(back, "inc") == [0.0, None, 1.0]


def test_writer_leaves_out_source_line(tmp_path: Path) -> None:
    table, well = read(put(tmp_path, las()))
    path = tmp_path / "again.las"
    WRITER.write(table, path, well)
    text = path.read_text()
    assert "source_line" not in text
    assert "Columns not written" not in text
    again, _ = read(path)
    assert again.drop_columns("source_line").equals(table.drop_columns("source_line"))


def test_writer_refuses_what_it_cannot_write(tmp_path: Path) -> None:
    path = tmp_path / "x.las"
    cases: list[tuple[pa.Table, WellMetadata, str]] = [
        (pa.table({"name": ["a"]}), WELL, "no numeric column"),
        (pa.table({"md": [1.0, math.inf]}), WELL, "infinite values"),
        (pa.table({"md": [1.0, None]}), WELL, "index column 'md' has missing values"),
        (pa.table({"a:b": [1.0]}), WELL, "cannot be a LAS curve"),
        (
            pa.table(
                {"md": [1.0]},
                schema=pa.schema([pa.field("md", pa.float64(), metadata={UNIT_KEY: b"m s"})]),
            ),
            WELL,
            "cannot be a LAS curve",
        ),
        (pa.table({"md": [1.0]}), WellMetadata(well="a\nb"), "line break"),
    ]
    grid = pa.field("b", pa.float64(), metadata={NORTH_KEY: b"grid"})
    true = pa.field("a", pa.float64(), metadata={NORTH_KEY: b"true"})
    mixed = pa.Table.from_arrays([pa.array([1.0]), pa.array([2.0])], schema=pa.schema([true, grid]))
    cases.append((mixed, WELL, "different north references"))
    for table, well, message in cases:
        with pytest.raises(ValueError, match=message):
            WRITER.write(table, path, well)


_finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
_value = _finite.filter(lambda v: v not in NULL_MARKERS)  # a null in every reader
_angle = _finite.filter(lambda v: v not in ANGLE_NULL_MARKERS)
_text = (
    st.text(st.characters(blacklist_categories=("Cc", "Cs", "Zl", "Zp")), min_size=1, max_size=12)
    .map(str.strip)
    .filter(bool)
)


@settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    rows=st.lists(
        st.tuples(_value, _angle, _angle, st.one_of(st.none(), _value)), min_size=1, max_size=20
    ),
    ref=st.sampled_from(["true", "grid", "magnetic"]),
    name=_text,
    company=_text,
    latitude=st.floats(-90, 90),
    elevation=st.one_of(st.none(), _finite),
)
def test_round_trip(
    tmp_path: Path,
    rows: list[tuple[float, float, float, float | None]],
    ref: str,
    name: str,
    company: str,
    latitude: float,
    elevation: float | None,
) -> None:
    md, inc, azi, tvd = (list(c) for c in zip(*rows, strict=True))
    md.sort()  # one path's depths run one way (the writer refuses an index turning back)
    table = _stations({"md": md, "inc": inc, "azi": azi}, ref)
    table = table.append_column(
        pa.field("tvd", pa.float64(), metadata={UNIT_KEY: b"m"}), pa.array(tvd, pa.float64())
    )
    well = WELL.model_copy(
        update={
            "well": name,
            "company": company,
            "latitude": latitude,
            "elevation": elevation,
            "north_reference": ref,
        }
    )
    path = tmp_path / "out.las"
    WRITER.write(table, path, well)
    back, back_well = read(path)
    assert back_well == well
    assert back.column_names == ["md", "inc", "azi", "tvd", "source_line"]
    for column_name in ("md", "inc", "azi", "tvd"):
        assert back.schema.field(column_name) == table.schema.field(column_name)
        assert back.schema.field(column_name).metadata == table.schema.field(column_name).metadata
    assert_exported(back, table, ["md", "inc", "azi", "tvd"])


@pytest.fixture(scope="module")
def simulated() -> pa.Table:
    spec = SimulationSpec.model_validate(
        {
            "name": "t",
            "seed": 3,
            "site": {
                "latitude": 61.25,
                "longitude": 73.4,
                "elevation": 120.0,
                "date": "2026-11-21",
                "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
            },
            "well": {"sections": [{"kind": "vertical", "length": 20}]},
            "tool": {"preset": "ideal"},
            "survey": {"mode": "point", "every": 10, "dwell": 1.0, "move_time": 0.5, "speed": 5.0},
        }
    )
    samples: pa.Table = simulate(spec).samples
    return samples


def test_round_trip_of_simulated_samples(tmp_path: Path, simulated: pa.Table) -> None:
    path = tmp_path / "samples.las"
    WRITER.write(simulated, path, WellMetadata(well="SIM", latitude=61.25))
    back, well = read(path, "samples")
    assert well == WellMetadata(well="SIM", latitude=61.25)
    assert back.drop_columns("source_line").schema.equals(simulated.schema, check_metadata=True)
    assert_exported(back, simulated)
    RawSamples.validate_table(back)


# --------------------------------------------------------------------------- fuzz

VALID = las(
    " DEPT.FT : depth\n INCL.DEG : inclination\n AZIM.DEG : azimuth (true north)\n GR.GAPI : gamma\n",
    "0.0 0.0 0.0 45\n100.5 1.25 45.5 -999.25\n201.0 2.5 46.0 50\n",
    well=" STRT.FT 0.0 : start\n STOP.FT 201.0 : stop\n STEP.FT 100.5 : step\n WELL. A-12 : well\n",
).encode()
_mutation = byte_mutations(len(VALID), b" \t\r\n#~.:-+eE0123456789,", lines=True)


def _lasio_curves(path: Path) -> list[np.ndarray] | None:
    """lasio's numeric curves, each also in every canonical unit its unit converts to;
    None when lasio fails or finds no data rows (e.g. a ``~a`` title, which it does not
    take for the data section)."""
    try:
        reference = lasio.read(str(path))
    except Exception:  # lasio fails in many ways on broken files: no reference then
        return None
    curves = [np.asarray(c.data) for c in reference.curves]
    if not curves or curves[0].size == 0:
        return None
    converted = []
    for curve, data in zip(reference.curves, curves, strict=True):
        if data.dtype.kind == "f":
            converted.append(data)
            for quantity in QUANTITIES:
                try:
                    converted.append(data * conversion_factor(curve.unit, quantity))
                except UnitError:
                    continue
    return converted


def test_valid_fuzz_seed_parses(fuzz_dir: Path) -> None:
    table, well = read(put(fuzz_dir, VALID))
    assert column(table, "md") == [0.0, 100.5 * 0.3048, 201.0 * 0.3048]
    assert well.well == "A-12"


@settings(max_examples=300, deadline=None, derandomize=True)
@given(mutations=st.lists(_mutation, min_size=1, max_size=3))
def test_fuzz_mutations_raise_typed_errors_or_read_what_lasio_reads(
    fuzz_dir: Path, mutations: list[tuple[str, int, int]]
) -> None:
    path = put(fuzz_dir, mutate_bytes(VALID, mutations))
    try:
        table, _ = read(path)
    except (InputFileError, UnitError):
        return
    assert table.num_rows >= 1
    assert table.column_names[-1] == "source_line"
    curves = _lasio_curves(path)
    if curves is None:
        return
    for name in table.column_names[:-1]:
        ours = as_nan(table, name)
        assert any(
            c.shape == ours.shape and np.array_equal(c, ours, equal_nan=True) for c in curves
        ), f"{name}: {ours} is none of lasio's curves"


@pytest.mark.parametrize(
    ("well", "null", "mnemonic"),
    [
        (" STRT.M 0 :\n STOP.M 200 :\n STEP.M 1e309 :\n", "-999.25", "STEP"),
        (" STRT.M -1e999 :\n", "-999.25", "STRT"),
        ("", "1e400", "NULL"),
    ],
)
def test_a_header_number_past_the_float_range_is_located(
    tmp_path: Path, well: str, null: str, mnemonic: str
) -> None:
    """Fuzz finding: STEP 1e309 (read as inf) ended in an OverflowError out of the range
    check (a ReaderError naming no file); such a number is refused at its header line."""
    text = las(well=well, null=null)
    err = failure(put(tmp_path, text))
    line = next(n for n, t in enumerate(text.splitlines(), 1) if t.startswith(f" {mnemonic}."))
    assert err.line == line and f"{mnemonic} " in str(err) and "too large for a number" in str(err)
