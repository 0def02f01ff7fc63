"""Listings of a real run: LAS 2.0 with a complete header read by lasio and by our reader,
values at their unit's decimals (:mod:`pipeline.io.precision`), the CSV listing read back (units, north reference, calculation lines, DLS told from the
dogleg by its unit) and the Parquet listing's metadata."""

from __future__ import annotations

import datetime as dt
import logging
from pathlib import Path

import lasio
import numpy as np
import pandas as pd
import pyarrow as pa
from export_support import SAMPLE

import pipeline as gp
from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.io.csv import read as read_csv
from pipeline.io.las import read_las
from pipeline.io.las.write import write_las
from pipeline.runner import RunResult
from pipeline.survey.calculation import calculation_of
from pipeline.tables import Stations
from pipeline.well import WellMetadata, well_of
from tests_support import export_tolerance

logging.getLogger("lasio").setLevel(logging.CRITICAL)
STATION_COLUMNS = ("md", "inc", "azi", "tvd", "north", "east", "dls")


def values(table: pa.Table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_numpy(), dtype=np.float64)


def assert_exported_values(got: np.ndarray, trajectory: pa.Table, name: str) -> None:
    """``got`` is column ``name`` as exported: within half a step of its unit's decimals."""
    unit = trajectory.schema.field(name).metadata[UNIT_KEY].decode()
    want = values(trajectory, name)
    assert np.all(np.abs(got - want) <= export_tolerance(unit, want)), name


def test_las_header_is_complete_for_lasio(exports_run: RunResult, trajectory: pa.Table):
    las = lasio.read(str(exports_run.out_dir / "trajectory.las"), mnemonic_case="preserve")
    well = {item.mnemonic: item for item in las.well}
    md = values(trajectory, "md")
    assert (well["STRT"].value, well["STOP"].value, well["STEP"].value) == (md[0], md[-1], 30.0)
    assert well["STRT"].unit == "m" and well["NULL"].value == -999.25
    expected = {
        "COMP": "Example Operator",
        "WELL": "J-12",
        "FLD": "Samotlor",
        "LOC": "61.25 N 73.4 E (WGS84)",
        "SRVC": "Gyro Services",
        "DATE": "2026-11-21",
        "UWI": "05-123-45678",
        "API": "05-123-45678",
        "LATI": 61.25,
        "LONG": 73.4,
        "DREF": "RKB",
        "EREF": 54.3,
        "TOOL": "gyro (example)",
    }
    assert {m: well[m].value for m in expected} == expected
    assert (well["LATI"].unit, well["LONG"].unit, well["EREF"].unit) == ("deg", "deg", "m")
    params = {item.mnemonic: (item.value, item.unit) for item in las.params}
    assert params == {
        "NREF": ("grid", ""),
        "DECL": (17.0, "deg"),
        "GRIDCONV": (1.25, "deg"),
        "DECLUSED": ("", "deg"),  # the site's declination was not applied to gyro azimuths
        "GRIDUSED": (1.25, "deg"),
        "MAGFIELD": ("", "nT"),  # a gyro run's well states no geomagnetic reference
        "MAGDIP": ("", "deg"),
        "METHOD": ("minimum curvature", ""),
        "VSAZ": (30.0, "deg"),
        "CONF": (0.9, ""),  # the uncertainty stage's confidence (exports_run)
        "ERRMODEL": ("GYRO-NS rev 5 (2020-10-08)", ""),  # its model, the bundled file's
        "TIEMD1": (md[0], "m"),  # its σ starts at the first station, at the wellhead
        "TIEBASIS1": ("wellhead", ""),
    }
    numeric = [f for f in trajectory.schema if pa.types.is_floating(f.type)]
    assert [c.mnemonic for c in las.curves] == [f.name for f in numeric]
    assert [c.unit for c in las.curves] == [f.metadata[UNIT_KEY].decode() for f in numeric]
    assert "grid north" in las.curves["azi"].descr
    for f in numeric:
        assert_exported_values(las[f.name], trajectory, f.name)


def test_las_round_trips_through_our_reader(exports_run: RunResult, trajectory: pa.Table):
    table, well = read_las(exports_run.out_dir / "trajectory.las", "stations", None)
    Stations.validate_table(table)
    for name in STATION_COLUMNS:
        assert_exported_values(values(table, name), trajectory, name)
    assert table.schema.field("azi").metadata[NORTH_KEY] == b"grid"
    original = well_of(trajectory)
    assert original is not None
    # every header field comes back (the wellbore, map coordinates and crs included)
    assert well == original


def test_las_location_api_and_absent_fields(tmp_path: Path, trajectory: pa.Table):
    path = tmp_path / "t.las"
    well = WellMetadata(well="S-1", latitude=-33.5, longitude=200.0, uwi="CA 100/01-02-003")
    write_las(trajectory.select(["md", "inc", "azi"]).replace_schema_metadata(None), path, well)
    las = lasio.read(str(path))
    assert las.well["LOC"].value == "33.5 S 160.0 W (WGS84)"
    assert (las.well["UWI"].value, las.well["API"].value) == ("CA 100/01-02-003", "")
    assert las.params["DECL"].value == "" and las.params["METHOD"].value == ""
    _, back = read_las(path, "stations", None)
    assert (back.latitude, back.longitude, back.declination) == (-33.5, 200.0, None)


def test_csv_listing_reads_back_with_units_and_north_reference(
    exports_run: RunResult, trajectory: pa.Table
):
    path = exports_run.out_dir / "trajectory.csv"
    head = path.read_text().splitlines()
    assert "# north_reference=grid" in head
    assert "# survey_method=minimum_curvature" in head and "# vs_azimuth=30.0 deg" in head
    header = next(line for line in head if line.startswith("md["))
    for f in trajectory.schema:
        assert f"{f.name}[{f.metadata[UNIT_KEY].decode()}]" in header.split(",")
    table, well = read_csv(path, "stations", None)
    for name in STATION_COLUMNS:  # dls[deg/30m] is the DLS, dogleg[deg] is not
        assert_exported_values(values(table, name), trajectory, name)
        assert (
            table.schema.field(name).metadata[UNIT_KEY]
            == trajectory.schema.field(name).metadata[UNIT_KEY]
        )
    assert table.schema.field("azi").metadata[NORTH_KEY] == b"grid"
    assert well == well_of(trajectory)
    assert well.survey_date == dt.date(2026, 11, 21)


def test_parquet_listing_keeps_units_north_reference_and_calculation(trajectory: pa.Table):
    for f in trajectory.schema:
        assert f.metadata[UNIT_KEY], f.name
    assert trajectory.schema.field("azi").metadata[NORTH_KEY] == b"grid"
    assert trajectory.schema.field("ellipse_azimuth").metadata[NORTH_KEY] == b"grid"
    calculation = calculation_of(trajectory)
    assert calculation is not None and calculation.vs_azimuth == 30.0
    well = well_of(trajectory)
    assert well is not None and well.grid_convergence == 1.25


def test_las_export_header_numbers_and_no_byte_order_mark(tmp_path: Path):
    """Issue 28 item 13: LOC read ``1.8870000000000005 E`` (the longitude's wrap into
    [-180, 180)) and the file began with a BOM (the north/east descriptions' minus sign);
    a UTF-8 export has none, even with a non-ASCII well name, and reads back."""
    stations = gp.read(SAMPLE)
    well = {"well": "Brønn-1", "latitude": 58.44, "longitude": 1.887}
    path = gp.write(gp.minimum_curvature(stations, well=well), tmp_path / "t.las")
    raw = path.read_bytes()
    assert raw.startswith(b"~Version")
    header = raw.decode("utf-8").split("~ASCII")[0]
    assert " LOC     .         58.44 N 1.887 E (WGS84)  : location\n" in header
    assert [line for line in header.splitlines() if not line.isascii()] == [
        " WELL    .         Brønn-1                  : well"
    ]
    _, back = read_las(path, "stations", None)
    assert (back.well, back.latitude, back.longitude) == ("Brønn-1", 58.44, 1.887)


def test_las_step_is_written_at_its_unit_decimals(tmp_path: Path):
    """md 1000.1, 1000.2: STEP 0.1, not the difference's 0.10000000000002274."""
    frame = pd.DataFrame({"md": [1000.1, 1000.2], "inc": [1.0, 1.1], "azi": [10.0, 11.0]})
    frame.attrs = {"units": {"md": "m", "inc": "deg", "azi": "deg"}, "north_reference": "true"}
    las = lasio.read(str(gp.write(frame, tmp_path / "s.las")))
    assert (las.well["STEP"].value, las.well["STEP"].unit) == (0.1, "m")
