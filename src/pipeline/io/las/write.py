"""The LAS writer: any table as a LAS 2.0 file.

LAS 2.0, unwrapped: ``~Version``; ``~Well`` with STRT/STOP/STEP (STEP 0 unless all steps are
exactly equal), NULL, COMP, WELL, FLD, LOC (the wellhead's coordinates as text), SRVC, DATE
(of trajectories begun on several days the first's, the description naming the last's),
UWI, API (the UWI when it is a US API number), LATI, LONG, DREF, EREF, TOOL, TOOLSN,
TOOLPRESET (the tool catalogue's entry, whose error magnitudes compassing takes), TOOLNAME,
WELLBORE, RUN, JOB, HZCS, X and Y (the wellhead's map coordinates, m, as LAS 3.0 names
them; items the well metadata lacks are written empty); ``~Parameter`` with NREF, DECL and
GRIDCONV (the well's magnetic declination and grid convergence, deg, east of true north positive),
DECLUSED and GRIDUSED (the declination and convergence applied to the azimuths), MAGFIELD
(nT) and MAGDIP (deg) (the geomagnetic reference the magnetometer checks take),
METHOD and VSAZ (the survey calculation method and vertical-section azimuth a trajectory
records, :mod:`pipeline.survey.calculation`), and CONF and ERRMODEL where the columns
state them (the confidence of the ``*_conf`` curves, the error model of the uncertainty
ones, :mod:`pipeline.uncertainty.stated`) and the TIE… items of where they start, each
survey's tie-on (:mod:`pipeline.io.las.tieon`); ``~Curve`` (mnemonic = column name, unit =
the field's ``unit`` metadata as stored, e.g. ``deg/h``; description = the field's
``description`` metadata, a log's own, else the canonical column's); ``~Other``;
``~ASCII`` with each float at its unit's decimals (:mod:`pipeline.io.precision`; others in
shortest round-trip form). The first (index) column is ``md``
for a stations-like table (md, inc and azi present), else ``time`` (raw samples dwell at one
depth: only their time increases), else ``md``, else the first numeric column (a log's
index); an index that turns back (a trajectory of several surveys: a sidetrack beside its
main bore, a re-survey from surface) is refused — a LAS file is one log along one path.
NULL is -999.25; NaN is written as NULL, and a value that is a null marker of
:mod:`pipeline.io.nulls` (-999.25, -9999.25; ±999.25… in an angle) is refused: every reader
would read it back as no value. Text columns are written as text (in double quotes when a
value holds a space, as lasio and gyropipe read them; a null as NULL), except a column the
LAS readers read, all as numbers (``survey``); those and boolean columns are left
out and named in ``~Other``; ``source_line`` (a line of the file read) is not written. A column
named ``NAME:2`` (how readers tell apart curves of one mnemonic) is written as ``NAME``. A
file holds one north reference: the azimuth columns' (else the well's), in NREF and in each
azimuth curve's description. Header numbers are written in shortest round-trip form,
STEP at its unit's decimals and the LOC text's degrees at 6 decimals. The file is UTF-8
without a byte-order mark (ASCII unless the well's or a column's own text is not: strict
LAS readers expect ``~V`` as the first bytes). A header line the reader would refuse for its
length (:func:`~pipeline.io.las.header.item_problem`) is refused.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv

from pipeline.contracts import DESCRIPTION_KEY, NORTH_KEY, UNIT_KEY
from pipeline.io.las.curves import KINDS
from pipeline.io.las.header import Item, item_problem
from pipeline.io.las.tieon import tie_on_items
from pipeline.io.mnemonics import CURVES
from pipeline.io.nulls import NULL_MARKERS, refuse_null_markers
from pipeline.io.precision import DECIMALS, for_export
from pipeline.survey.calculation import calculation_of
from pipeline.uncertainty.stated import file_statements
from pipeline.uncertainty.tieon import tie_on_of
from pipeline.version import __version__
from pipeline.well import WellMetadata

NULL = NULL_MARKERS[0]
"""The NULL value written (-999.25)."""
EXACT_INTEGER = 2**53
"""The largest integer a double (what LAS readers read every value as) holds exactly."""
READ_AS_NUMBERS = frozenset(name for kind in KINDS.values() for name in kind.columns)
"""The columns the LAS readers read, each as numbers (a survey id from a numeric curve): a
text column of one of these names is not written."""

STATED = {
    "confidence": ("CONF", "confidence of the *_conf curves (probability)"),
    "error_model": ("ERRMODEL", "error model of the position uncertainty curves"),
}
"""~Parameter mnemonic and description of what the columns state once for the file
(:func:`~pipeline.uncertainty.stated.file_statements`)."""

_MNEMONIC = re.compile(r"[^\s.:~#][^\s.:]*")
_REPEATED = re.compile(r"(.+):[0-9]+")
_API = re.compile(r"[0-9]{2}-?[0-9]{3}-?[0-9]{5}(?:-?[0-9]{2}){0,2}")
_UNIT = re.compile(r"[^\s:]*")


def write_las(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write ``table`` as LAS 2.0 (see the module docstring); floats at their unit's
    precision (:mod:`pipeline.io.precision`)."""
    table = for_export(table)
    written = [f for f in table.schema if _writable_type(f)]
    numeric = [f for f in written if not pa.types.is_string(f.type)]
    if not numeric:
        raise ValueError("no numeric column to write: a LAS file needs a numeric index")
    if written[0] not in numeric and written[0].name not in ("md", "time"):
        raise ValueError(  # a log indexed by text: another curve would become its index
            f"the first column {written[0].name!r} is text: a LAS file's index is its first "
            "curve, a number"
        )
    curve_lines = {f.name: _curve_line(f) for f in written}
    index = _index_column([f.name for f in numeric])
    written.sort(key=lambda f: f.name != index)
    values = {f.name: _writable(table.column(f.name), f.name) for f in written}
    if values[index].null_count:
        raise ValueError(f"index column {index!r} has missing values")
    _one_path(table, index, values[index])
    refuse_null_markers(values)
    null = NULL
    north = _written_north(numeric, well)
    text = _header_text(table, written, values[index], null, north, well, curve_lines)
    filled = [
        v if not v.null_count else v.fill_null(repr(null) if pa.types.is_string(v.type) else null)
        for v in values.values()
    ]
    texts = [i for i, v in enumerate(filled) if pa.types.is_string(v.type)]
    with path.open("wb") as fh:
        fh.write(text.encode())
        if not texts:
            pacsv.write_csv(
                pa.table({f"c{i}": v for i, v in enumerate(filled)}),
                fh,
                pacsv.WriteOptions(include_header=False, delimiter=" ", quoting_style="none"),
            )
            return
        cells = [
            _text_cells(v) if i in texts else pc.cast(v, pa.string()) for i, v in enumerate(filled)
        ]
        lines = pc.binary_join_element_wise(*cells, " ").to_pylist()
        fh.write("".join(f"{line}\n" for line in lines).encode())


def _one_path(table: pa.Table, index: str, values: pa.ChunkedArray) -> None:
    """Refuse an index that turns back (up a log logged down, or down one logged up): a LAS
    file is one log along one path, and one of a trajectory of several surveys (a sidetrack
    beside its main bore, a re-survey from surface) would read as one path whose depth goes
    back (the survey column is not written)."""
    x = values.to_numpy(zero_copy_only=False)
    steps = (x[1:] > x[:-1]).astype(np.int8) - (x[1:] < x[:-1])  # no overflow of 1e308 steps
    moving = steps[steps != 0]
    back = np.flatnonzero(steps == -moving[0]) if moving.size else moving
    if not back.size:
        return
    row = int(back[0]) + 1
    where = f"{index} runs back from {x[row - 1]:g} to {x[row]:g} at row {row}"
    if "survey" in table.column_names:
        surveys = table.column("survey").to_pylist()
        where += f" (survey {surveys[row - 1]!r} to {surveys[row]!r})"
    raise ValueError(
        f"{where}: a LAS file is one log along one path; write each survey on its own, or "
        "as CSV, WITSML or Parquet, which keep the survey column"
    )


def _writable_type(f: pa.Field) -> bool:
    """Numbers, and text unless a column the LAS readers read (as numbers)."""
    if pa.types.is_floating(f.type) or pa.types.is_integer(f.type):
        return True
    return (pa.types.is_string(f.type) or pa.types.is_large_string(f.type)) and (
        f.name not in READ_AS_NUMBERS
    )


def _curve_line(f: pa.Field) -> str:
    """The ~Curve line of a column. A mnemonic ending in '.' or holding a space (``COND.``,
    ``I. RES.``, as LAS files have them) is written against its unit (``COND..MS/M``), as
    lasio's grammar reads it back; a name or unit it would not read back is refused."""
    mnemonic, unit, descr = _mnemonic(f.name), _field_unit(f), _description(f)
    if _MNEMONIC.fullmatch(mnemonic) and _UNIT.fullmatch(unit):
        return _line(mnemonic, unit, None, descr)
    from lasio.reader import read_header_line  # imported on use: lasio is slow to import

    line = f" {mnemonic}.{unit:<8} {'':<24} : {descr}"
    try:
        parsed = read_header_line(line.strip(), section_name="Curves")
    except AttributeError:
        parsed = {}
    if (parsed.get("name"), parsed.get("unit")) != (mnemonic, unit) or ":" in mnemonic:
        raise ValueError(
            f"column {f.name!r} (unit {unit!r}) cannot be a LAS curve: a name or unit with "
            "':', or a unit with spaces"
        )
    return _readable(line, Item(mnemonic, unit, "", descr, 0))


def _mnemonic(name: str) -> str:
    """The curve mnemonic of a column: ``NAME:2`` (a reader's name for a repeated mnemonic)
    is ``NAME``."""
    found = _REPEATED.fullmatch(name)
    return found[1] if found else name


def _field_unit(f: pa.Field) -> str:
    unit = (f.metadata or {}).get(UNIT_KEY)
    return unit.decode() if unit else ""


def _index_column(names: list[str]) -> str:
    """md for a stations-like table, else time, else md, else the first column."""
    if {"md", "inc", "azi"} <= set(names):
        return "md"
    return next((n for n in ("time", "md") if n in names), names[0])


def _writable(column: pa.ChunkedArray, name: str) -> pa.Array:
    """A column as int64 (integers without nulls), float64 (NaN as null) or text."""
    array = column.combine_chunks()
    if pa.types.is_string(array.type) or pa.types.is_large_string(array.type):
        return array.cast(pa.string())
    if pa.types.is_integer(array.type) and not array.null_count:
        whole = array.cast(pa.int64())
        bounds = pc.min_max(whole)
        if len(whole) and max(-bounds["min"].as_py(), bounds["max"].as_py()) > EXACT_INTEGER:
            raise ValueError(
                f"column {name!r} holds integers beyond ±2^53: a LAS value is read as a "
                "double, which cannot hold them exactly"
            )
        return whole
    values = array.cast(pa.float64()).to_numpy(zero_copy_only=False)
    if np.isinf(values).any():
        raise ValueError(f"column {name!r} has infinite values: LAS cannot hold them")
    return pa.array(values, mask=np.isnan(values))


def _text_cells(values: pa.Array) -> pa.Array:
    """Text values as ~A cells: as they are, or in double quotes when they hold a space
    or are empty (in single quotes when they also hold a double quote)."""
    cells = []
    for value in values.to_pylist():
        if "\n" in value or "\r" in value or ('"' in value and "'" in value):
            raise ValueError(f"text value {value!r} cannot be a LAS cell")
        elif value and not re.search(r"[\s\"'#~]", value):
            cells.append(value)
        else:
            cells.append(f"'{value}'" if '"' in value else f'"{value}"')
    return pa.array(cells, pa.string())


def _written_north(fields: list[pa.Field], well: WellMetadata) -> str | None:
    refs = {f.metadata[NORTH_KEY].decode() for f in fields if NORTH_KEY in (f.metadata or {})}
    if len(refs) > 1:
        raise ValueError(
            f"columns have different north references {sorted(refs)}: one file holds one"
        )
    return refs.pop() if refs else well.north_reference


def _header_text(
    table: pa.Table,
    written: list[pa.Field],
    index: pa.Array,
    null: float,
    north: str | None,
    well: WellMetadata,
    curve_lines: dict[str, str],
) -> str:
    """~Version, ~Well, ~Curve and ~Other sections and the ~ASCII title."""
    values = index.to_numpy(zero_copy_only=False)
    with np.errstate(over="ignore", invalid="ignore"):  # a step past the float range: inf
        steps = np.diff(values)
    regular = (
        steps.size > 0 and steps[0] != 0 and np.isfinite(steps[0]) and np.all(steps == steps[0])
    )
    step = steps[0] if regular else 0
    first, last = (values[0], values[-1]) if values.size else (None, None)
    unit = _field_unit(written[0])
    if regular and unit in DECIMALS:  # md 1000.1, 1000.2: 0.1, not 0.10000000000002274
        step = round(float(step), DECIMALS[unit])
    meta = well.model_dump(mode="json")
    calculation = calculation_of(table)
    stated = file_statements(table.schema)
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
        _line("DATE", "", meta["survey_date"], _date_description(well)),
        _line("UWI", "", meta["uwi"], "unique well identifier"),
        _line("API", "", _api(well.uwi), "API number"),
        _line("LATI", "deg", meta["latitude"], "latitude (WGS84)"),
        _line("LONG", "deg", meta["longitude"], "longitude east (WGS84)"),
        _line("DREF", "", meta["depth_reference"], "depth reference"),
        _line("EREF", "m", meta["elevation"], "elevation of the depth reference above MSL"),
        _line("TOOL", "", meta["tool_type"], "survey tool type"),
        _line("TOOLSN", "", meta["tool_serial"], "survey tool serial number"),
        _line("TOOLPRESET", "", meta["tool_preset"], "tool catalogue entry of the survey tool"),
        _line("TOOLNAME", "", meta["tool_name"], "survey tool name"),
        _line("WELLBORE", "", meta["wellbore"], "wellbore"),
        _line("RUN", "", meta["run_number"], "survey run number"),
        _line("JOB", "", meta["job_number"], "service company's job number"),
        _line("HZCS", "", meta["crs"], "horizontal coordinate reference system"),
        _line("X", "m", meta["easting"], "wellhead easting in HZCS"),
        _line("Y", "m", meta["northing"], "wellhead northing in HZCS"),
        "~Parameter Information",
        _line("NREF", "", north, "north reference of the azimuths"),
        _line("DECL", "deg", meta["declination"], "magnetic declination, east of true north +"),
        _line(
            "GRIDCONV", "deg", meta["grid_convergence"], "grid convergence, east of true north +"
        ),
        _line("DECLUSED", "deg", meta["declination_applied"], "declination applied to azimuths"),
        _line(
            "GRIDUSED", "deg", meta["grid_convergence_applied"], "convergence applied to azimuths"
        ),
        _line("MAGFIELD", "nT", meta["magnetic_field"], "geomagnetic total field"),
        _line("MAGDIP", "deg", meta["magnetic_dip"], "geomagnetic dip, down +"),
        _line(
            "METHOD", "", calculation and calculation.method.replace("_", " "), "survey calculation"
        ),
        _line(
            "VSAZ",
            "deg",
            calculation and calculation.vs_azimuth,
            "vertical section azimuth (origin: wellhead)",
        ),
        *(_line(STATED[key][0], "", value, STATED[key][1]) for key, value in stated.items()),
        *(_line(*item) for item in _tie_on_items(table, written)),
        "~Curve Information",
        *(curve_lines[f.name] for f in written),
        "~Other",
        f"Written by gyropipe {__version__}.",
    ]
    dropped = [f"{f.name} ({f.type})" for f in table.schema if f not in written]
    if dropped:
        lines.append("Columns not written: " + ", ".join(dropped))
    lines.append("~ASCII " + " ".join(_mnemonic(f.name) for f in written))
    return "\n".join(lines) + "\n"


def _tie_on_items(
    table: pa.Table, written: list[pa.Field]
) -> list[tuple[str, str, str | float, str]]:
    """The ~Parameter items of the table's tie-on record (:mod:`pipeline.io.las.tieon`)."""
    record = tie_on_of(table)
    if record is None:
        return []
    return tie_on_items(record, with_survey=any(f.name == "survey" for f in written))


def _location(well: WellMetadata) -> str | None:
    """The wellhead as text, e.g. ``61.25 N 73.4 E (WGS84)``: degrees at their export
    decimals (:data:`~pipeline.io.precision.DECIMALS`), so 1.887 is not 1.8870000000000005
    once the longitude is taken into [-180, 180)."""
    if well.latitude is None or well.longitude is None:
        return None
    lon = (well.longitude + 180.0) % 360.0 - 180.0
    north = f"{_degrees(well.latitude)} {'N' if well.latitude >= 0 else 'S'}"
    return f"{north} {_degrees(lon)} {'E' if lon >= 0 else 'W'} (WGS84)"


def _degrees(value: float) -> str:
    """``abs(value)`` at the export decimals of degrees, shortest form (``160.0``)."""
    return repr(round(abs(value), DECIMALS["deg"]) + 0.0)


def _api(uwi: str | None) -> str | None:
    """The UWI when it is a US API number (10, 12 or 14 digits)."""
    if uwi is None or not _API.fullmatch(uwi):
        return None
    return uwi


def _date_description(well: WellMetadata) -> str:
    """DATE's description: of trajectories begun on several days it says so (LAS has one
    DATE, the first day's)."""
    if well.survey_date_last is None:
        return "survey date"
    return f"survey date of the first trajectory; the last began {well.survey_date_last}"


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
    line = f" {mnemonic:<8}.{unit:<8} {text:<24} : {descr}"
    return _readable(line, Item(mnemonic, unit, text, descr, 0))


def _readable(line: str, item: Item) -> str:
    """``line`` (of ``item``) if the reader takes its length, else a ValueError: gyropipe
    writes no header line it refuses to read back (:func:`~pipeline.io.las.header.item_problem`)."""
    reason = item_problem(item, line)
    if reason is not None:
        raise ValueError(reason)
    return line


def _description(f: pa.Field) -> str:
    own = (f.metadata or {}).get(DESCRIPTION_KEY)
    text = own.decode() if own else CURVES[f.name].description if f.name in CURVES else f.name
    north = (f.metadata or {}).get(NORTH_KEY)
    return text + (f" ({north.decode()} north)" if north else "")
