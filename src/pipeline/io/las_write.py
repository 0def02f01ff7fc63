"""The LAS writer: any numeric table as a LAS 2.0 file.

LAS 2.0, unwrapped: ``~Version``; ``~Well`` with STRT/STOP/STEP (STEP 0 unless all steps are
exactly equal), NULL, COMP, WELL, FLD, LOC (the wellhead's coordinates as text), SRVC, DATE,
UWI, API (the UWI when it is a US API number), LATI, LONG, DREF, EREF, TOOL, TOOLSN (items
the well metadata lacks are written empty); ``~Parameter`` with NREF, DECL and GRIDCONV (the
well's magnetic declination and grid convergence, deg, east of true north positive),
METHOD and VSAZ (the survey calculation method and vertical-section azimuth a trajectory
records, :mod:`pipeline.survey.calculation`); ``~Curve`` (mnemonic = column name, unit =
the field's ``unit`` metadata as stored, e.g. ``deg/h``); ``~Other``;
``~ASCII`` with each value in shortest round-trip form. The first (index) column is ``md``
for a stations-like table (md, inc and azi present), else ``time`` (raw samples dwell at one
depth: only their time increases), else ``md``, else the first numeric column. NULL is
-999.25, or the first of -9999.25, -99999.25… that no value equals; NaN is written as NULL.
Text and boolean columns cannot be held by ``~A``: they are left out and named in
``~Other``; ``source_line`` (a line of the file read) is not written. A file holds one north
reference: the azimuth columns' (else the well's), in NREF and in each azimuth curve's
description.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv

from pipeline.contracts import NORTH_KEY, SOURCE_LINE, UNIT_KEY
from pipeline.io.mnemonics import CURVES
from pipeline.survey.calculation import calculation_of
from pipeline.version import __version__
from pipeline.well import WellMetadata

NULL_CHOICES = (-999.25, -9999.25, -99999.25, -999999.25, -9999999.25)
"""NULL values the writer may use, in order of preference."""

_MNEMONIC = re.compile(r"[A-Za-z0-9_][^\s.:]*")
_API = re.compile(r"[0-9]{2}-?[0-9]{3}-?[0-9]{5}(?:-?[0-9]{2}){0,2}")
_UNIT = re.compile(r"[^\s:]*")


def write_las(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write the numeric columns of ``table`` as LAS 2.0 (see the module docstring)."""
    numeric = [
        f
        for f in table.schema
        if f.name != SOURCE_LINE and (pa.types.is_floating(f.type) or pa.types.is_integer(f.type))
    ]
    if not numeric:
        raise ValueError("no numeric column to write: LAS ~A holds numbers only")
    for f in numeric:
        if not _MNEMONIC.fullmatch(f.name) or not _UNIT.fullmatch(_field_unit(f)):
            raise ValueError(
                f"column {f.name!r} (unit {_field_unit(f)!r}) cannot be a LAS curve: a name "
                "or unit with spaces, '.' or ':'"
            )
    index = _index_column([f.name for f in numeric])
    numeric.sort(key=lambda f: f.name != index)
    values = {f.name: _writable(table.column(f.name), f.name) for f in numeric}
    if values[index].null_count:
        raise ValueError(f"index column {index!r} has missing values")
    null = _null_value(values.values())
    text = _header_text(table, numeric, values[index], null, _written_north(numeric, well), well)
    filled = pa.table(
        {name: v.fill_null(null) if v.null_count else v for name, v in values.items()}
    )
    with path.open("wb") as fh:
        fh.write(text.encode())
        pacsv.write_csv(
            filled,
            fh,
            pacsv.WriteOptions(include_header=False, delimiter=" ", quoting_style="none"),
        )


def _field_unit(f: pa.Field) -> str:
    unit = (f.metadata or {}).get(UNIT_KEY)
    return unit.decode() if unit else ""


def _index_column(names: list[str]) -> str:
    """md for a stations-like table, else time, else md, else the first column."""
    if {"md", "inc", "azi"} <= set(names):
        return "md"
    return next((n for n in ("time", "md") if n in names), names[0])


def _writable(column: pa.ChunkedArray, name: str) -> pa.Array:
    """A column as int64 (integers without nulls) or float64 (NaN as null)."""
    array = column.combine_chunks()
    if pa.types.is_integer(array.type) and not array.null_count:
        return array.cast(pa.int64())
    values = array.cast(pa.float64()).to_numpy(zero_copy_only=False)
    if np.isinf(values).any():
        raise ValueError(f"column {name!r} has infinite values: LAS cannot hold them")
    return pa.array(values, mask=np.isnan(values))


def _null_value(values: Iterable[pa.Array]) -> float:
    """The first NULL choice that no value equals."""
    arrays = [a.to_numpy(zero_copy_only=False) for a in values]
    for null in NULL_CHOICES:
        if not any(np.any(a == null) for a in arrays):
            return null
    raise ValueError(f"every NULL choice {NULL_CHOICES} is a value of the table")


def _written_north(fields: list[pa.Field], well: WellMetadata) -> str | None:
    refs = {f.metadata[NORTH_KEY].decode() for f in fields if NORTH_KEY in (f.metadata or {})}
    if len(refs) > 1:
        raise ValueError(
            f"columns have different north references {sorted(refs)}: one file holds one"
        )
    return refs.pop() if refs else well.north_reference


def _header_text(
    table: pa.Table,
    numeric: list[pa.Field],
    index: pa.Array,
    null: float,
    north: str | None,
    well: WellMetadata,
) -> str:
    """~Version, ~Well, ~Curve and ~Other sections and the ~ASCII title."""
    values = index.to_numpy(zero_copy_only=False)
    steps = np.diff(values)
    regular = (
        steps.size > 0 and steps[0] != 0 and np.isfinite(steps[0]) and np.all(steps == steps[0])
    )
    step = steps[0] if regular else 0
    first, last = (values[0], values[-1]) if values.size else (None, None)
    unit = _field_unit(numeric[0])
    meta = well.model_dump(mode="json")
    calculation = calculation_of(table)
    lines = [
        "~Version Information",
        _line("VERS", "", "2.0", "CWLS log ASCII Standard - version 2.0"),
        _line("WRAP", "", "NO", "one line per index step"),
        "~Well Information",
        _line("STRT", unit, first, "first index value"),
        _line("STOP", unit, last, "last index value"),
        _line("STEP", unit, step, "index step, 0 if irregular"),
        _line("NULL", "", null, "null value"),
        _line("COMP", "", meta["company"], "company"),
        _line("WELL", "", meta["well"], "well"),
        _line("FLD", "", meta["field"], "field"),
        _line("LOC", "", _location(well), "location"),
        _line("SRVC", "", meta["service_company"], "service company"),
        _line("DATE", "", meta["survey_date"], "survey date"),
        _line("UWI", "", meta["uwi"], "unique well identifier"),
        _line("API", "", _api(well.uwi), "API number"),
        _line("LATI", "deg", meta["latitude"], "latitude (WGS84)"),
        _line("LONG", "deg", meta["longitude"], "longitude east (WGS84)"),
        _line("DREF", "", meta["depth_reference"], "depth reference"),
        _line("EREF", "m", meta["elevation"], "elevation of the depth reference above MSL"),
        _line("TOOL", "", meta["tool_type"], "survey tool type"),
        _line("TOOLSN", "", meta["tool_serial"], "survey tool serial number"),
        "~Parameter Information",
        _line("NREF", "", north, "north reference of the azimuths"),
        _line("DECL", "deg", meta["declination"], "magnetic declination, east of true north +"),
        _line(
            "GRIDCONV", "deg", meta["grid_convergence"], "grid convergence, east of true north +"
        ),
        _line(
            "METHOD", "", calculation and calculation.method.replace("_", " "), "survey calculation"
        ),
        _line(
            "VSAZ",
            "deg",
            calculation and calculation.vs_azimuth,
            "vertical section azimuth (origin: wellhead)",
        ),
        "~Curve Information",
        *(_line(f.name, _field_unit(f), None, _description(f)) for f in numeric),
        "~Other",
        f"Written by gyropipe {__version__}.",
    ]
    dropped = [
        f"{f.name} ({f.type})" for f in table.schema if f not in numeric and f.name != SOURCE_LINE
    ]
    if dropped:
        lines.append("Columns not written (~A holds numbers only): " + ", ".join(dropped))
    lines.append("~ASCII " + " ".join(f.name for f in numeric))
    return "\n".join(lines) + "\n"


def _location(well: WellMetadata) -> str | None:
    """The wellhead as text, e.g. ``61.25 N 73.4 E (WGS84)``."""
    if well.latitude is None or well.longitude is None:
        return None
    lon = (well.longitude + 180.0) % 360.0 - 180.0
    north = f"{abs(well.latitude)!r} {'N' if well.latitude >= 0 else 'S'}"
    return f"{north} {abs(lon)!r} {'E' if lon >= 0 else 'W'} (WGS84)"


def _api(uwi: str | None) -> str | None:
    """The UWI when it is a US API number (10, 12 or 14 digits)."""
    if uwi is None or not _API.fullmatch(uwi):
        return None
    return uwi


def _line(mnemonic: str, unit: str, value: object, descr: str) -> str:
    """One header item line; ``value`` None leaves it empty."""
    if value is None or isinstance(value, str):
        text = value or ""
    elif isinstance(value, int | np.integer):
        text = str(int(value))
    else:
        text = repr(float(value))  # type: ignore[arg-type]
    if "\n" in text or "\r" in text:
        raise ValueError(f"{mnemonic} {text!r} has a line break: a LAS header line cannot")
    return f" {mnemonic:<8}.{unit:<8} {text:<24} : {descr}"


def _description(f: pa.Field) -> str:
    text = CURVES[f.name].description if f.name in CURVES else f.name
    north = (f.metadata or {}).get(NORTH_KEY)
    return text + (f" ({north.decode()} north)" if north else "")
