"""Built-in LAS plugin: a reader of LAS 1.2/2.0 (and single-log 3.0) files as survey
stations or raw sensor samples, and a LAS 2.0 writer of any numeric table.

Reading
-------
* **Header** — the lines before the ``~A`` (LAS 3: ``~Log_Data``) title are split into
  sections at their ``~`` titles; each item line of ``~V``, ``~W``, ``~C`` and ``~P`` (LAS 3:
  ``~Log_Definition``, ``~Log_Parameter``) is parsed with lasio's header grammar
  (:func:`lasio.reader.read_header_line`: ``MNEM.UNIT  VALUE : DESCRIPTION``), keeping the
  raw text and line of every item (``lasio.read`` turns a UWI ``0012`` into ``12``, and
  even with ``ignore_data`` scans the whole file: 4 s for 100 MB). LAS 1.x ``~W`` items
  other than STRT/STOP/STEP/NULL hold their value after the colon, as the 1.2 standard
  (and lasio) says. Other sections (``~O``, unknown ones) are skipped.
* **Text** — UTF-8 (BOM or not) when the bytes are valid UTF-8, else Windows-1252 (Latin-1
  plus ``°``, ``µ``…); a byte neither accepts, or a NUL byte, is an error naming its line.
* **Curves** — a mnemonic names a canonical column through
  :func:`pipeline.io.mnemonics.canonical_name` (``DEPT``→md, ``AZIM``→azi, ``GX``→acc_x,
  ``WX``→gyro_x, ``BZ``→mag_z…) or the option ``columns``; an azimuth mnemonic may end in
  its north reference (``AZTN``, ``AZGN``, ``AZI_MN``). Other curves are left out. Units
  come from the curve line (the option ``units`` wins) and are converted to canonical units
  with :func:`pipeline.units.conversion_factor`; a needed curve without a known unit is an
  error saying how to declare it.
* **North reference** (stations) — named by the azimuth mnemonic, a word of its description
  (``Azimuth (true north)``, ``Grid azimuth``, ``MN``), an ``NREF`` item (or ``NORTHREF``,
  ``AZIREF``, ``AZREF``) in ``~W``/``~P``, or the option ``north_reference``: all must
  agree; ``default_north_reference`` applies when none names one.
* **Data** — :func:`_fast_values` (numpy + ``pyarrow.csv``; ≥ 10× faster than ``lasio.read``,
  see ``benchmarks/bench_las.py``) reads plain blocks of numbers; :func:`_slow_values`, the
  careful path, reads the rest (wrapped files, comment or blank lines, lone CR line ends,
  text in unread curves, LAS 3 delimiters) and locates every error by line. Both give every
  number correctly rounded, so values equal lasio's. ``NULL`` items and the option
  ``null_values`` become nulls (compared as numbers: ``-999.2500`` is ``-999.25``). A row
  with too many or too few values, a cell that is not a finite number, a null index value and
  an index contradicting STRT/STOP/STEP (a truncated file, a lost row) are errors with their
  line: no value is ever dropped or shifted. Each row keeps its file line in ``source_line``.
* **Well metadata** — WELL, UWI (else API), FLD, COMP, SRVC, TOOL, TOOLSN; LAT/LATI/LATITUDE
  and LON/LONG/LONGITUDE in decimal degrees (in the item's unit) or degrees, minutes and
  seconds (``61 15 00.5 N``, ``73°24'30"E``); DATE as ISO or another unambiguous form
  (``13-DEC-1986``, ``Dec 13, 1986``, ``13/12/1986``; a two-digit year after a month name
  is the latest such year not after today; ``05/06/2024`` is refused as ambiguous);
  elevation from EREF, else the item of the depth reference (DREF, LMF or DMF: KB→EKB,
  DF→EDF, GL→EGL, else ELEV), else the only one of EKB/EDF/EGL/ELEV (several and no
  reference item: an error); DECL (MAGDEC, DECLINATION) and GRIDCONV (CONV, CONVERGENCE,
  GRIDCORR) in degrees or the item's angle unit. ``north_reference`` is the one the file
  names (an option's is not the file's).

Writing
-------
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

import calendar
import datetime as dt
import re
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from pipeline.contracts import NORTH_KEY, SOURCE_LINE, UNIT_KEY, TableContract
from pipeline.errors import InputFileError, UnitError
from pipeline.hookspecs import hookimpl
from pipeline.io.conventions import Conventions, to_canonical
from pipeline.io.mnemonics import CURVES, canonical_name, normalise
from pipeline.io.sniffing import file_head
from pipeline.registry import ReaderDef, WriterDef
from pipeline.survey.calculation import calculation_of
from pipeline.tables import RawSamples, Stations
from pipeline.units import canonical_unit, conversion_factor, is_unit_of
from pipeline.version import __version__
from pipeline.well import NORTH_WORDS, DefaultNorthReference, NorthReference, WellMetadata

Floats = NDArray[np.float64]
Lines = NDArray[np.int64]
Mask = NDArray[np.bool_]
Bytes = NDArray[np.uint8]

SNIFF_BYTES = 64 * 1024
BOM = b"\xef\xbb\xbf"
SHOWN = 8
NULL_CHOICES = (-999.25, -9999.25, -99999.25, -999999.25, -9999999.25)
"""NULL values the writer may use, in order of preference."""

Role = Literal["version", "well", "curves", "parameter", "data"]
SECTION_NAMES: dict[Role, str] = {
    "version": "Version",
    "well": "Well",
    "curves": "Curves",
    "parameter": "Parameter",
    "data": "Data",
}
"""lasio's name of each section role (its header grammar depends on it)."""

NORTH_SUFFIXES: dict[str, NorthReference] = {"TN": "true", "GN": "grid", "MN": "magnetic"}
"""Endings of an azimuth mnemonic naming its north reference."""
NORTH_ITEMS = ("NREF", "NORTHREF", "AZIREF", "AZREF")
TEXT_ITEMS: dict[str, tuple[str, ...]] = {
    "well": ("WELL",),
    "uwi": ("UWI", "API"),
    "field": ("FLD", "FIELD"),
    "company": ("COMP",),
    "service_company": ("SRVC",),
    "tool_type": ("TOOL",),
    "tool_serial": ("TOOLSN",),
}
"""Well metadata text fields and the mnemonics holding them, preferred first."""
ANGLE_ITEMS = {
    "declination": ("DECL", "MAGDEC", "DECLINATION"),
    "grid_convergence": ("GRIDCONV", "CONV", "CONVERGENCE", "GRIDCORR"),
}
"""Well metadata angles (deg, in the item's unit) and the mnemonics holding them."""
COORDINATE_ITEMS = {
    "latitude": (("LAT", "LATI", "LATITUDE"), "NS"),
    "longitude": (("LON", "LONG", "LONGITUDE"), "EW"),
}
"""Coordinate fields: their mnemonics and hemisphere letters (positive, negative)."""
REFERENCE_ITEMS = ("DREF", "LMF", "DMF")
ELEVATION_ITEMS: dict[str, str | None] = {
    "EREF": None,
    "EKB": "KB",
    "EDF": "DF",
    "EGL": "GL",
    "ELEV": None,
}
"""Elevation items and the depth reference each implies."""
REFERENCE_ELEVATION = {"KB": "EKB", "RKB": "EKB", "DF": "EDF", "RDF": "EDF", "GL": "EGL"}

_DATA_TITLE = re.compile(rb"^[ \t]*~(?:A|LOG_DATA)", re.IGNORECASE | re.MULTILINE)
_FAST_BYTES = b"0123456789.eE+- \t\r\n"
"""Bytes the fast path reads; any other sends the data section to the careful path."""
_TAB_TO_SPACE = bytes.maketrans(b"\t", b" ")
_NUMBER = r"^[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?$"
_DMS_NUMBER = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)"
_DMS_MARKS = re.compile(r"[°º'′\"″:\s]|DEG")
_MONTHS = {name.upper(): i for i, name in enumerate(calendar.month_name) if name}
_MNEMONIC = re.compile(r"[A-Za-z0-9_][^\s.:]*")
_API = re.compile(r"[0-9]{2}-?[0-9]{3}-?[0-9]{5}(?:-?[0-9]{2}){0,2}")
_UNIT = re.compile(r"[^\s:]*")


# ---------------------------------------------------------------------------- options


class LasOptions(BaseModel):
    """Options of the LAS reader; every one may be left to the file."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    columns: dict[str, str] = Field(
        default_factory=dict,
        description="curve mnemonic of a canonical column, e.g. {md: DEPT, gyro_x: GYRO1}",
    )
    units: dict[str, str] = Field(
        default_factory=dict,
        description="unit of a canonical column's curve, e.g. {md: ft}; overrides the file's",
    )
    north_reference: NorthReference | None = Field(
        None, description="north reference of the azimuths (true, grid or magnetic)"
    )
    default_north_reference: DefaultNorthReference = None
    conventions: Conventions = Field(
        default_factory=Conventions,
        description="vendor axis and sign conventions of the sensor curves (samples)",
    )
    null_values: list[float] = Field(
        default_factory=list, description="values meaning 'no value' besides the file's NULL"
    )

    @field_validator("columns")
    @classmethod
    def _known_columns(cls, columns: dict[str, str]) -> dict[str, str]:
        unknown = sorted(set(columns) - set(CURVES))
        if unknown:
            raise ValueError(f"unknown column(s) {unknown}; known: {', '.join(CURVES)}")
        return columns

    @field_validator("units")
    @classmethod
    def _valid_units(cls, units: dict[str, str]) -> dict[str, str]:
        for name, unit in units.items():
            curve = CURVES.get(name)
            if curve is None or curve.quantity is None:
                raise ValueError(f"{name!r} is not a canonical column with a unit")
            try:
                conversion_factor(unit, curve.quantity)
            except UnitError as exc:
                raise ValueError(f"{name}: {exc}") from None
        return units


# ----------------------------------------------------------------------------- model


@dataclass(frozen=True)
class Item:
    """One header line: upper-case mnemonic, unit, value and description as written."""

    mnemonic: str
    unit: str
    value: str
    descr: str
    line: int


@dataclass(frozen=True)
class Header:
    """The header sections read."""

    version: float
    wrapped: bool
    delimiter: str
    """SPACE, COMMA or TAB (LAS 3 ``DLM``)"""
    well: list[Item]
    parameters: list[Item]
    curves: list[Item]

    def find(self, path: Path, *mnemonics: str) -> Item | None:
        """The first item with a value among ``mnemonics`` (preferred first), in ~Well then
        ~Parameter. One mnemonic given twice with different values is an error."""
        for section in (self.well, self.parameters):
            for mnemonic in mnemonics:
                items = [i for i in section if i.mnemonic == mnemonic and i.value]
                if len({i.value for i in items}) > 1:
                    raise InputFileError(
                        path,
                        f"{mnemonic} is given twice with different values "
                        f"({items[0].value!r} on line {items[0].line}, {items[1].value!r})",
                        line=items[1].line,
                    )
                if items:
                    return items[0]
        return None


@dataclass(frozen=True)
class Source:
    """A LAS file split at its data title: the header lines, and the file's bytes with the
    offset of the data (the line after the title), not copied."""

    header: list[str]
    title_line: int
    """1-based line of the data section title (0: there is none)"""
    raw: bytes
    start: int


@dataclass(frozen=True)
class Data:
    """Values of the curves read (by ~Curve position) and the file line of each row."""

    values: dict[int, Floats]
    lines: Lines


@dataclass(frozen=True)
class Kind:
    """A table kind the reader makes: its contract, its columns in order, the required ones
    and the one that may not be null (the survey's own index)."""

    contract: type[TableContract]
    columns: tuple[str, ...]
    required: tuple[str, ...]
    key: str


KINDS = {
    "stations": Kind(
        Stations,
        ("survey", "md", "inc", "azi", "tvd", "north", "east", "dls"),
        ("md", "inc", "azi"),
        "md",
    ),
    "samples": Kind(
        RawSamples,
        tuple(RawSamples.model_fields),
        ("time", "gyro_x", "acc_x", "acc_y", "acc_z"),
        "time",
    ),
}
INTEGER_COLUMNS = frozenset({"station", "position"})
TEXT_COLUMNS = frozenset({"survey"})


# ---------------------------------------------------------------------------- reader


def read_las(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Read a LAS file as ``stations`` (md m, inc/azi deg; tvd/north/east m and dls deg/30m
    when present) or ``samples`` (time s, gyros deg/h, accelerometers m/s2, magnetometers
    nT, md m, frame_angle deg), plus ``source_line`` (the file line of each row)."""
    if kind not in KINDS:
        raise ValueError(f"the las reader reads kinds {sorted(KINDS)}, not {kind!r}")
    spec = KINDS[kind]
    opts = LasOptions.model_validate(options or {})
    source = _load(path)
    header = _parse_header(path, source.header)
    if source.title_line == 0:
        raise InputFileError(path, "no ~A (data) section")
    declared = _declared_north(path, header)
    chosen = _choose(path, header, spec, opts, declared)
    factors = {name: _factor(path, header.curves[i], name, opts) for name, i in chosen.items()}
    north, file_north = None, _one_north(path, declared)
    if "azi" in chosen:
        north, file_north = _azimuth_north(path, header.curves[chosen["azi"]], declared, opts)
    data = _read_data(path, source, header, sorted({0, *chosen.values()}))
    nulls = _nulls(path, header, opts)
    masks = {i: np.isin(values, nulls) for i, values in data.values.items()}
    _check_index(path, header, data, masks, [0, chosen[spec.key]])
    _check_range(path, header, data.values[0], data.lines, nulls)
    table = _make_table(spec, _columns(path, spec, header, chosen, data, masks, factors), north)
    if kind == "samples":
        try:
            table = to_canonical(table, opts.conventions)
        except ValueError as exc:
            raise InputFileError(path, f"option conventions: {exc}") from None
    return table, _well_metadata(path, header, file_north)


def sniff(path: Path) -> bool:
    """True if the first line that is neither blank nor a ``#`` comment opens ``~V``."""
    head = file_head(path, SNIFF_BYTES)
    if head is None:
        return False
    for line in head.removeprefix(BOM).splitlines():
        text = line.strip()
        if text and not text.startswith(b"#"):
            return text[:2].upper() == b"~V"
    return False


# ------------------------------------------------------------------------- file text


def _load(path: Path) -> Source:
    """The file's header lines (decoded) and data bytes."""
    try:
        raw = path.read_bytes().removeprefix(BOM)
    except OSError as exc:
        raise InputFileError(path, f"cannot read the file: {exc.strerror or exc}") from None
    if not raw or raw.isspace():
        raise InputFileError(path, "the file is empty")
    head = raw[:SNIFF_BYTES]
    if head.count(b"\r") != head.count(b"\r\n"):  # old Mac line ends: lone CRs
        raw = raw.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    title = _DATA_TITLE.search(raw)
    if title is None:
        return Source(_split_lines(_decode(path, raw, 1)), 0, b"", 0)
    end = raw.find(b"\n", title.start())
    lines = _split_lines(_decode(path, raw[: title.start()], 1))
    return Source(lines[:-1], len(lines), raw, len(raw) if end < 0 else end + 1)


def _decode(path: Path, data: bytes, first_line: int) -> str:
    """UTF-8 text if ``data`` is valid UTF-8, else Windows-1252; ``data`` starts on file
    line ``first_line``."""
    if b"\0" in data:
        line = first_line + data[: data.index(b"\0")].count(b"\n")
        raise InputFileError(path, "NUL byte: this is not a LAS text file", line=line)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        pass
    try:
        return data.decode("cp1252")
    except UnicodeDecodeError as exc:
        line = first_line + data[: exc.start].count(b"\n")
        raise InputFileError(
            path,
            f"byte 0x{data[exc.start]:02x} is neither UTF-8 nor Windows-1252 (Latin-1) text",
            line=line,
        ) from None


def _split_lines(text: str) -> list[str]:
    """Lines of ``text`` split at LF, CRLF or a lone CR."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


# ---------------------------------------------------------------------------- header


def _parse_header(path: Path, lines: list[str]) -> Header:
    sections: dict[Role, list[Item]] = {role: [] for role in SECTION_NAMES}
    role: Role | None = None
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        if text.startswith("~"):
            role = _section_role(text)
        elif role is not None:
            sections[role].append(_item(path, text, number, role))
    version, wrapped, delimiter = _version(path, sections["version"])
    if not sections["curves"]:
        raise InputFileError(path, "no curves: the ~Curve section is missing or empty")
    well = sections["well"]
    if version < 2:
        well = [_las1_well_item(item) for item in well]
    return Header(version, wrapped, delimiter, well, sections["parameter"], sections["curves"])


def _section_role(title: str) -> Role | None:
    """The role of a section from its ``~`` title (None: a section not read)."""
    name = title[1:].strip().upper()
    if name.startswith("LOG_DEFINITION") or (name.startswith("C") and "_" not in name):
        return "curves"
    if name.startswith("LOG_PARAMETER") or (name.startswith("P") and "_" not in name):
        return "parameter"
    if name.startswith(("A", "LOG_DATA")):
        return "data"
    if name.startswith("V"):
        return "version"
    if name.startswith("W"):
        return "well"
    return None


def _item(path: Path, text: str, number: int, role: Role) -> Item:
    from lasio.reader import read_header_line  # imported on use: lasio is slow to import

    try:
        parsed = read_header_line(text, section_name=SECTION_NAMES[role])
    except AttributeError:  # lasio's grammar does not match the line
        raise InputFileError(
            path,
            f"cannot read header line {text!r}: expected 'MNEMONIC.UNIT  VALUE : DESCRIPTION'",
            line=number,
        ) from None
    unit = parsed["unit"]
    if len(unit) >= 2 and unit[0] + unit[-1] in ("[]", "()"):  # as lasio strips them
        unit = unit[1:-1].strip()
    return Item(parsed["name"].upper(), unit, parsed["value"], parsed["descr"], number)


def _las1_well_item(item: Item) -> Item:
    """A LAS 1.x ~Well item holds its value after the colon (except STRT/STOP/STEP/NULL);
    a value written on one side only is taken where it is."""
    if item.mnemonic in ("STRT", "STOP", "STEP", "NULL") or not item.descr:
        return item
    return Item(item.mnemonic, item.unit, item.descr, item.value, item.line)


def _version(path: Path, items: list[Item]) -> tuple[float, bool, str]:
    """LAS version (2.0 if not given), whether the data are wrapped, the data delimiter."""

    def value(mnemonic: str, default: str) -> tuple[str, int]:
        found = [i for i in items if i.mnemonic == mnemonic and i.value]
        return (found[0].value.upper(), found[0].line) if found else (default, 0)

    vers, line = value("VERS", "2.0")
    version = float(vers) if re.fullmatch(r"[0-9]+(\.[0-9]*)?", vers) else 0.0
    if int(version) not in (1, 2, 3):
        raise InputFileError(path, f"VERS {vers!r}: not a LAS version (1.2, 2.0, 3.0)", line=line)
    wrap, line = value("WRAP", "NO")
    if wrap not in ("YES", "NO"):
        raise InputFileError(path, f"WRAP {wrap!r}: expected YES or NO", line=line)
    delimiter, line = value("DLM", "SPACE")
    if delimiter not in ("SPACE", "COMMA", "TAB"):
        raise InputFileError(path, f"DLM {delimiter!r}: expected SPACE, COMMA or TAB", line=line)
    return version, wrap == "YES", delimiter


# ---------------------------------------------------------------------------- curves


def _recognise(item: Item) -> str | None:
    """The canonical column a curve's mnemonic names, if any."""
    return "azi" if _suffix_north(item.mnemonic) else canonical_name(item.mnemonic)


def _suffix_north(mnemonic: str) -> NorthReference | None:
    """The north reference an azimuth mnemonic ends with (``AZTN``, ``AZI_GN``), if any."""
    key = normalise(mnemonic)
    for suffix, ref in NORTH_SUFFIXES.items():
        stem = key.removesuffix(suffix)
        if stem != key and (stem == "AZ" or canonical_name(stem) == "azi"):
            return ref
    return None


def _choose(
    path: Path,
    header: Header,
    spec: Kind,
    opts: LasOptions,
    declared: list[tuple[str, NorthReference]],
) -> dict[str, int]:
    """The ~Curve position of each column of the kind the file has."""
    curves = header.curves
    chosen: dict[str, int] = {}
    for name, mnemonic in opts.columns.items():
        if name not in spec.columns:
            raise InputFileError(
                path, f"option columns: {name} is not read here (read: {', '.join(spec.columns)})"
            )
        matches = [i for i, c in enumerate(curves) if normalise(c.mnemonic) == normalise(mnemonic)]
        if len(matches) != 1:
            raise InputFileError(
                path,
                f"option columns: {name}: {mnemonic!r} names "
                + (f"{len(matches)} curves" if matches else "no curve")
                + f"; curves: {_mnemonics(curves)}",
                line=curves[matches[1]].line if matches else 0,
            )
        chosen[name] = matches[0]
    found: dict[str, list[int]] = {}
    for i, curve in enumerate(curves):
        guess = _recognise(curve)
        if guess in spec.columns and guess not in chosen and i not in chosen.values():
            found.setdefault(guess, []).append(i)
    refs = {ref for _, ref in declared} | {opts.north_reference}
    for name, indices in found.items():
        if len(indices) > 1 and name == "azi":  # the one of the declared north reference
            indices = [i for i in indices if set(_curve_north(curves[i])) & refs] or indices
        quantity = CURVES[name].quantity
        if len(indices) > 1 and quantity is not None:  # the unit tells: DOGLEG.deg is no DLS
            indices = [i for i in indices if is_unit_of(curves[i].unit, quantity)] or indices
        if len(indices) > 1:
            raise InputFileError(
                path,
                f"several curves look like {name}: "
                f"{', '.join(curves[i].mnemonic for i in indices)}; choose one with the option "
                f"columns (e.g. columns: {{{name}: {curves[indices[0]].mnemonic}}})"
                + (" or north_reference" if name == "azi" else ""),
                line=curves[indices[1]].line,
            )
        chosen[name] = indices[0]
    _require(path, header, spec, chosen)
    return chosen


def _require(path: Path, header: Header, spec: Kind, chosen: dict[str, int]) -> None:
    missing = [name for name in spec.required if name not in chosen]
    if not missing:
        return
    accepted = "; ".join(f"{n}: {', '.join(CURVES[n].aliases)}" for n in missing)
    hint = (
        " (samples need time: a depth-indexed log is not raw samples)" if "time" in missing else ""
    )
    raise InputFileError(
        path,
        f"no curve for {', '.join(missing)}{hint}; curves: {_mnemonics(header.curves)}; "
        f"accepted mnemonics: {accepted}; or name the curve with the option columns "
        f"(e.g. columns: {{{missing[0]}: MNEMONIC}})",
        line=header.curves[0].line,
    )


def _mnemonics(curves: list[Item]) -> str:
    names = [c.mnemonic for c in curves]
    more = f" and {len(names) - SHOWN} more" if len(names) > SHOWN else ""
    return ", ".join(names[:SHOWN]) + more


def _factor(path: Path, curve: Item, name: str, opts: LasOptions) -> float:
    """Factor from the curve's unit (the option ``units`` wins) to the canonical unit."""
    quantity = CURVES[name].quantity
    if quantity is None:
        return 1.0
    unit = opts.units.get(name) or curve.unit
    canonical = canonical_unit(quantity)
    how = (
        f"declare it in the ~Curve line (e.g. '{curve.mnemonic}.{canonical} : ...') or with "
        f"the option units (e.g. units: {{{name}: {canonical}}})"
    )
    if not unit:
        raise InputFileError(
            path, f"curve {curve.mnemonic} ({name}) has no unit: {how}", curve.line, curve.mnemonic
        )
    try:
        return conversion_factor(unit, quantity)
    except UnitError as exc:
        raise InputFileError(
            path, f"curve {curve.mnemonic} ({name}): {exc}; {how}", curve.line, curve.mnemonic
        ) from None


# ------------------------------------------------------------------- north reference


def _north_word(path: Path, item: Item) -> NorthReference:
    """The reference an NREF-like item's value names: one of the :data:`NORTH_WORDS`."""
    words = {w for w in re.split(r"[^0-9a-z]+", item.value.casefold()) if w} - {"north"}
    if len(words) == 1 and (word := words.pop()) in NORTH_WORDS:
        return NORTH_WORDS[word]
    raise InputFileError(
        path, f"{item.mnemonic} {item.value!r}: expected true, grid or magnetic", line=item.line
    )


def _declared_north(path: Path, header: Header) -> list[tuple[str, NorthReference]]:
    """(where, reference) of each NREF-like item."""
    return [
        (f"{item.mnemonic} on line {item.line}", _north_word(path, item))
        for item in header.well + header.parameters
        if item.mnemonic in NORTH_ITEMS and item.value
    ]


def _curve_north(item: Item) -> set[NorthReference]:
    """North references an azimuth curve names by its mnemonic's ending or description."""
    words = re.split(r"[^0-9a-z]+", item.descr.casefold())
    refs = {NORTH_WORDS[w] for w in words if w in NORTH_WORDS}
    suffix = _suffix_north(item.mnemonic)
    return refs | {suffix} if suffix else refs


def _one_north(
    path: Path, sources: list[tuple[str, NorthReference]], curve: Item | None = None
) -> NorthReference | None:
    """The one north reference ``sources`` ((where, reference)) name, if any."""
    refs = sorted({ref for _, ref in sources})
    if len(refs) > 1:
        raise InputFileError(
            path,
            "conflicting north references: " + ", ".join(f"{r} ({s})" for s, r in sources),
            curve.line if curve else 0,
            curve.mnemonic if curve else "",
        )
    return refs[0] if refs else None


def _azimuth_north(
    path: Path, azi: Item, declared: list[tuple[str, NorthReference]], opts: LasOptions
) -> tuple[NorthReference, NorthReference | None]:
    """The azimuths' north reference, and the one the file itself names."""
    in_file = [(f"curve {azi.mnemonic} on line {azi.line}", r) for r in _curve_north(azi)]
    in_file += declared
    option = [("option north_reference", opts.north_reference)] if opts.north_reference else []
    north = _one_north(path, in_file + option, azi) or opts.default_north_reference
    if north is None:
        raise InputFileError(
            path,
            f"no north reference for the azimuths: name it in the curve description "
            f"('{azi.mnemonic}.DEG : Azimuth (true north)'), add a ~Well line "
            "'NREF.  grid : north reference', or set the option north_reference "
            "(or the well's north_reference)",
            azi.line,
            azi.mnemonic,
        )
    return north, _one_north(path, in_file, azi)


# ------------------------------------------------------------------------------ data


def _read_data(path: Path, source: Source, header: Header, wanted: list[int]) -> Data:
    """Values of the ``wanted`` curves: the fast path when it can read the data section,
    else the careful path."""
    first = source.title_line + 1
    if header.version < 3 and not header.wrapped and header.delimiter == "SPACE":
        fast = _fast_values(source.raw, source.start, len(header.curves), wanted)
        if fast is not None:
            values, rows = fast
            return Data(values, np.arange(first, first + rows, dtype=np.int64))
    text = _decode(path, source.raw[source.start :], first)
    return _slow_values(path, header, _split_lines(text), source.title_line, wanted)


def _fast_values(
    raw: bytes, start: int, n: int, wanted: list[int]
) -> tuple[dict[int, Floats], int] | None:
    """The fast path: values of the ``wanted`` of ``n`` curves in ``raw[start:]`` and the
    row count, or None when it cannot prove it reads them as the careful path would.

    It reads blocks of numbers, spaces, tabs and LF or CRLF line ends: tabs become spaces,
    CRs go, a vectorised pass (:func:`_pack_spaces`) leaves one space between values and
    none at line ends, and ``pyarrow.csv`` parses the rows (one-space delimiter, float64
    correctly rounded as by Python's ``float``; the first curve is always read, so a blank
    line is an empty value). A parse error (a blank line, a wrong value count, a token like
    ``1-2``), a row count other than the line count or a non-finite value (``1e999``)
    hands the block to the careful path, which reports it.
    """
    if len(raw.translate(None, _FAST_BYTES)) != len(raw[:start].translate(None, _FAST_BYTES)):
        return None  # a byte other than _FAST_BYTES in the data
    crs = raw.find(b"\r", start) >= 0
    if crs and raw.count(b"\r", start) != raw.count(b"\r\n", start):
        return None  # lone CRs
    if crs or raw.find(b"\t", start) >= 0:
        raw, start = raw[start:].translate(_TAB_TO_SPACE, b"\r"), 0
    packed = _pack_spaces(np.frombuffer(raw, np.uint8, offset=start))
    if packed.size == 0:
        return {i: np.empty(0) for i in wanted}, 0
    names = [f"c{i}" for i in range(n)]
    read = [names[i] for i in wanted]
    try:
        table = pacsv.read_csv(
            pa.BufferReader(pa.py_buffer(packed)),
            read_options=pacsv.ReadOptions(column_names=names),
            parse_options=pacsv.ParseOptions(
                delimiter=" ", quote_char=False, ignore_empty_lines=False
            ),
            convert_options=pacsv.ConvertOptions(
                column_types=dict.fromkeys(read, pa.float64()),
                include_columns=read,
                null_values=[],
                strings_can_be_null=False,
                check_utf8=False,
            ),
        )
    except pa.ArrowInvalid:
        return None
    rows = int(np.count_nonzero(packed == 10)) + 1
    values = {i: table.column(names[i]).to_numpy() for i in wanted}
    if table.num_rows != rows or not all(np.isfinite(v).all() for v in values.values()):
        return None
    return values, rows


def _pack_spaces(a: Bytes) -> Bytes:
    """Bytes of space-separated lines with each run of spaces made one space and none at
    the start or end of a line or of the block."""
    keep = np.empty(a.size, dtype=bool)
    np.greater(a[:-1], 32, out=keep[1:])  # a space after a value
    keep[:1] = False
    keep |= a != 32
    packed = a[keep]
    if packed.size > 1:
        before_end = packed[1:] == 10
        before_end &= packed[:-1] == 32
        if before_end.any():  # a space ending a line
            keep = np.ones(packed.size, dtype=bool)
            keep[:-1] = ~before_end
            packed = packed[keep]
    content: Bytes = packed[: _content_end(packed)]
    return content


def _content_end(a: Bytes) -> int:
    """Index after the last byte that is neither a space nor a line end."""
    for tail in (a[-4096:], a):
        found = np.flatnonzero(tail > 32)
        if found.size:
            return a.size - tail.size + int(found[-1]) + 1
    return 0


def _slow_values(
    path: Path, header: Header, lines: list[str], title_line: int, wanted: list[int]
) -> Data:
    """The careful path: rows from lines (wrapped or not, any delimiter; comment and blank
    lines skipped), every value checked as a number with its line."""
    numbered = _data_lines(path, header, lines, title_line)
    rows = (
        _wrapped_rows(path, numbered, len(header.curves))
        if header.wrapped
        else _unwrapped_rows(path, header, numbered)
    )
    cells: dict[int, list[str]] = {i: [] for i in wanted}
    starts: list[int] = []
    for line, row in rows:
        starts.append(line)
        for i in wanted:
            cells[i].append(row[i])
    lines_of = np.asarray(starts, dtype=np.int64)
    return Data(
        {i: _numbers(path, cells[i], lines_of, header.curves[i].mnemonic) for i in wanted},
        lines_of,
    )


def _data_lines(
    path: Path, header: Header, lines: list[str], title_line: int
) -> Iterator[tuple[int, list[str]]]:
    """(file line, values) of each data line up to the end of the data section."""
    split = _splitter(header)
    for number, line in enumerate(lines, start=title_line + 1):
        text = line.replace("\x1a", "").strip()  # ^Z: an old DOS end-of-file mark
        if not text or text.startswith("#"):
            continue
        if text.startswith("~"):
            if _section_role(text) == "data":
                raise InputFileError(
                    path,
                    f"a second data section (the first starts on line {title_line}): a LAS "
                    "file has one",
                    line=number,
                )
            if header.version >= 3:
                return
            raise InputFileError(
                path,
                f"section {text.split()[0]!r} after the ~A section: ~A must be the last",
                line=number,
            )
        yield number, split(text)


def _splitter(header: Header) -> Callable[[str], list[str]]:
    """Splits a data line into values: at whitespace (LAS 1.2/2.0), else as lasio splits
    LAS 3 lines (DLM SPACE/TAB honour quotes, COMMA splits at commas)."""
    if header.version < 3 and header.delimiter == "SPACE":
        return str.split
    from lasio.reader import define_line_splitter

    split = define_line_splitter(header.delimiter)
    return lambda text: ["".join(t).strip() for t in split(text)]


def _unwrapped_rows(
    path: Path, header: Header, numbered: Iterable[tuple[int, list[str]]]
) -> Iterator[tuple[int, list[str]]]:
    n = len(header.curves)
    for number, values in numbered:
        if len(values) != n:
            raise InputFileError(
                path,
                f"expected {n} values (one per curve: {_mnemonics(header.curves)}), "
                f"got {len(values)}",
                line=number,
            )
        yield number, values


def _wrapped_rows(
    path: Path, numbered: Iterable[tuple[int, list[str]]], n: int
) -> Iterator[tuple[int, list[str]]]:
    """Rows of wrapped data: each starts with its index value alone on a line and takes
    the next lines until it has ``n`` values; a row's line is its index line."""
    row: list[str] = []
    start = 0
    for number, values in numbered:
        if not row:
            if len(values) != 1:
                raise InputFileError(
                    path,
                    f"wrapped data (WRAP YES): a row starts with its index value alone on a "
                    f"line, got {len(values)} values",
                    line=number,
                )
            start = number
        row += values
        if len(row) > n:
            raise InputFileError(
                path,
                f"wrapped data: the row of line {start} has {len(row)} values here, more "
                f"than the {n} curves",
                line=number,
            )
        if len(row) == n:
            yield start, row
            row = []
    if row:
        raise InputFileError(
            path,
            f"wrapped data: the last row has {len(row)} of {n} values (truncated file?)",
            line=start,
        )


def _numbers(path: Path, cells: list[str], lines: Lines, mnemonic: str) -> Floats:
    """float64 values of one curve's cells; a cell that is not a finite decimal number
    raises with its line."""
    strings = pa.array(cells, pa.string())
    bad = pc.invert(pc.match_substring_regex(strings, _NUMBER))
    if pc.any(bad).as_py():
        row = int(np.flatnonzero(bad.to_numpy(zero_copy_only=False))[0])
        raise InputFileError(
            path, f"expected a number, got {cells[row]!r}", line=int(lines[row]), column=mnemonic
        )
    values: Floats = pc.cast(strings, pa.float64()).to_numpy()
    infinite = np.flatnonzero(~np.isfinite(values))
    if infinite.size:
        row = int(infinite[0])
        raise InputFileError(
            path, f"{cells[row]!r} is out of range", line=int(lines[row]), column=mnemonic
        )
    return values


# ----------------------------------------------------------------- nulls and the index


def _nulls(path: Path, header: Header, opts: LasOptions) -> list[float]:
    """Values meaning 'no value': every NULL item of ~Well/~Parameter and the option's."""
    items = [i for i in header.well + header.parameters if i.mnemonic == "NULL" and i.value]
    return [_header_number(path, item) for item in items] + list(opts.null_values)


def _header_number(path: Path, item: Item) -> float:
    if re.fullmatch(_NUMBER, item.value):
        return float(item.value)
    raise InputFileError(path, f"{item.mnemonic} {item.value!r} is not a number", line=item.line)


def _check_index(
    path: Path, header: Header, data: Data, masks: dict[int, Mask], keys: list[int]
) -> None:
    """Rows exist; the index (first curve) and the kind's key column have no nulls."""
    if data.lines.size == 0:
        raise InputFileError(path, "no data rows in the ~A section")
    for i in keys:
        nulls = np.flatnonzero(masks[i])
        if nulls.size:
            curve = header.curves[i]
            raise InputFileError(
                path,
                f"null value {data.values[i][nulls[0]]:g} in curve {curve.mnemonic}: every row "
                f"needs its {'index' if i == 0 else curve.mnemonic} value"
                + (f" ({nulls.size} null rows)" if nulls.size > 1 else ""),
                line=int(data.lines[nulls[0]]),
                column=curve.mnemonic,
            )


def _check_range(
    path: Path, header: Header, index: Floats, lines: Lines, nulls: list[float]
) -> None:
    """The index (first curve, in its unit) agrees with STRT, STOP and STEP where they are
    given and not null, within the rounding of their written digits (STEP: or 1 %)."""
    curve = header.curves[0]
    declared: dict[str, tuple[float, float, int]] = {}
    for mnemonic in ("STRT", "STOP", "STEP"):
        item = header.find(path, mnemonic)
        ratio = _unit_ratio(item.unit, curve.unit) if item else None
        if item is None or ratio is None or _header_number(path, item) in nulls:
            continue
        value = _header_number(path, item) * ratio
        declared[mnemonic] = (value, _half_unit(item.value) * abs(ratio), item.line)
    for mnemonic, row, what in (("STRT", 0, "first"), ("STOP", -1, "last")):
        if mnemonic in declared:
            value, tolerance, line = declared[mnemonic]
            if abs(index[row] - value) > tolerance + 1e-12 * abs(value):
                raise InputFileError(
                    path,
                    f"{mnemonic} is {value:g} but the {what} index value ({curve.mnemonic}) "
                    f"is {index[row]:g} on line {lines[row]}"
                    + (": the file may be truncated" if row else ""),
                    line=line if row == 0 else int(lines[row]),
                )
    step, tolerance, _ = declared.get("STEP", (0.0, 0.0, 0))
    if step != 0 and index.size > 1:
        steps = np.diff(index)
        bad = np.flatnonzero(np.abs(steps - step) > max(tolerance, 0.01 * abs(step)))
        if bad.size:
            k = int(bad[0])
            raise InputFileError(
                path,
                f"STEP is {step:g} but the index steps by {steps[k]:g} from line {lines[k]} to "
                "this line: a row may be missing or repeated (STEP 0 means irregular steps)",
                line=int(lines[k + 1]),
            )


def _unit_ratio(unit: str, index_unit: str) -> float | None:
    """Factor from ``unit`` to ``index_unit`` (1 when either is blank); None if unknown."""
    if not unit or not index_unit or unit.casefold() == index_unit.casefold():
        return 1.0
    for quantity in ("length", "time"):
        try:
            return conversion_factor(unit, quantity) / conversion_factor(index_unit, quantity)
        except UnitError:
            continue
    return None


def _half_unit(text: str) -> float:
    """Half a unit of the last written digit of a number (its rounding)."""
    try:
        exponent = Decimal(text).as_tuple().exponent
    except InvalidOperation:
        return 0.0
    return 0.5 * 10.0**exponent if isinstance(exponent, int) else 0.0


# ----------------------------------------------------------------------------- table


def _columns(
    path: Path,
    spec: Kind,
    header: Header,
    chosen: dict[str, int],
    data: Data,
    masks: dict[int, Mask],
    factors: dict[str, float],
) -> dict[str, pa.Array]:
    """The table's columns in canonical units, in the kind's order, with nulls."""
    columns: dict[str, pa.Array] = {}
    for name in (n for n in spec.columns if n in chosen):
        i = chosen[name]
        values, mask = data.values[i], masks[i]
        if name in INTEGER_COLUMNS:
            columns[name] = _integers(path, values, mask, data.lines, header.curves[i])
        elif name in TEXT_COLUMNS:
            columns[name] = _labels(values, mask)
        else:
            scaled = values * factors[name] if factors[name] != 1.0 else values
            columns[name] = pa.array(scaled, mask=mask if mask.any() else None)
    columns[SOURCE_LINE] = pa.array(data.lines)
    return columns


def _integers(path: Path, values: Floats, mask: Mask, lines: Lines, curve: Item) -> pa.Array:
    bad = np.flatnonzero(~mask & ((values != np.round(values)) | (np.abs(values) > 2.0**53)))
    if bad.size:
        raise InputFileError(
            path,
            f"expected a whole number, got {values[bad[0]]!r}",
            line=int(lines[bad[0]]),
            column=curve.mnemonic,
        )
    return pa.array(np.where(mask, 0, values).astype(np.int64), mask=mask if mask.any() else None)


def _labels(values: Floats, mask: Mask) -> pa.Array:
    """Text labels (survey ids) of a numeric curve: ``3.0`` → ``'3'``."""
    return pa.array(
        [
            None if null else f"{v:.0f}" if v.is_integer() else repr(v)
            for v, null in zip(values.tolist(), mask.tolist(), strict=True)
        ],
        pa.string(),
    )


def _make_table(spec: Kind, columns: dict[str, pa.Array], north: str | None) -> pa.Table:
    """The contract's table; columns outside the contract get their canonical unit."""
    table = spec.contract.compiled().make_table(columns, north_reference=north)
    known = {c.name for c in spec.contract.compiled().columns}
    fields = []
    for f in table.schema:
        quantity = CURVES[f.name].quantity if f.name in CURVES else None
        if f.name not in known and quantity is not None:
            f = f.with_metadata({UNIT_KEY: canonical_unit(quantity).encode()})
        fields.append(f)
    return pa.Table.from_arrays(table.columns, schema=pa.schema(fields))


# -------------------------------------------------------------------- well metadata


def _well_metadata(path: Path, header: Header, north: NorthReference | None) -> WellMetadata:
    """Well metadata from ~Well, then ~Parameter items; ``north`` is the file's."""
    found: dict[str, tuple[Any, Item]] = {}
    for name, mnemonics in TEXT_ITEMS.items():
        if (item := header.find(path, *mnemonics)) is not None:
            found[name] = (item.value, item)
    for name, (mnemonics, hemispheres) in COORDINATE_ITEMS.items():
        if (item := header.find(path, *mnemonics)) is not None:
            found[name] = (_coordinate(path, item, hemispheres), item)
    for name, mnemonics in ANGLE_ITEMS.items():
        if (item := header.find(path, *mnemonics)) is not None:
            found[name] = (_header_number(path, item) * _angle_factor(path, item), item)
    if (item := header.find(path, "DATE")) is not None:
        found["survey_date"] = (_date(path, item), item)
    elevation, reference = _elevation(path, header)
    if elevation is not None:
        found["elevation"] = elevation
    if reference is not None:
        found["depth_reference"] = reference
    for name, (value, item) in found.items():
        try:
            WellMetadata.model_validate({name: value})
        except ValidationError as exc:
            raise InputFileError(
                path, f"{item.mnemonic} {item.value!r}: {exc.errors()[0]['msg']}", line=item.line
            ) from None
    return WellMetadata(north_reference=north, **{n: v for n, (v, _) in found.items()})


def _angle_factor(path: Path, item: Item) -> float:
    """Degrees per unit of an angle item (no unit: degrees)."""
    try:
        return conversion_factor(item.unit, "angle") if item.unit else 1.0
    except UnitError as exc:
        raise InputFileError(path, f"{item.mnemonic}: {exc}", line=item.line) from None


def _coordinate(path: Path, item: Item, hemispheres: str) -> float:
    """Degrees of a latitude/longitude: a decimal number (in the item's unit, default deg)
    or degrees, minutes and seconds, with an optional hemisphere letter (S and W: −)."""

    def fail(reason: str) -> InputFileError:
        return InputFileError(
            path,
            f"{item.mnemonic} {item.value!r}: {reason}; write decimal degrees (61.25, -73.4) "
            "or degrees, minutes and seconds (61 15 00.0 N)",
            line=item.line,
        )

    text = item.value.strip().upper()
    sign = 1.0
    if found := re.fullmatch(rf"([{hemispheres}])\s*(.*)|(.*?)\s*([{hemispheres}])", text):
        text = found[2] if found[1] else found[3]
        sign = -1.0 if (found[1] or found[4]) == hemispheres[1] else 1.0
        if text.startswith(("-", "+")):
            raise fail("both a sign and a hemisphere")
    try:
        if not re.fullmatch(_NUMBER, text):
            return sign * _dms(text)
        return sign * float(text) * (conversion_factor(item.unit, "angle") if item.unit else 1.0)
    except (ValueError, UnitError) as exc:
        raise fail(str(exc)) from None


def _dms(text: str) -> float:
    """Degrees of degrees-minutes(-seconds) text (marks ° ' " or spaces; sign on degrees)."""
    numbers = re.findall(_DMS_NUMBER, text)
    if _DMS_MARKS.sub("", re.sub(_DMS_NUMBER, "", text)) or not 2 <= len(numbers) <= 3:
        raise ValueError("not a coordinate")
    degrees, *rest = (float(n) for n in numbers)
    if not degrees.is_integer() or any(
        r >= 60 or n[0] in "+-" for r, n in zip(rest, numbers[1:], strict=True)
    ):
        raise ValueError("minutes and seconds must be in [0, 60) after whole degrees")
    magnitude = abs(degrees) + sum(r / 60.0**k for k, r in enumerate(rest, start=1))
    return -magnitude if numbers[0].startswith("-") else magnitude


def _date(path: Path, item: Item) -> dt.date:
    """The date of a DATE item (a time of day after it is ignored)."""
    text = re.sub(
        r"[T\s]+\d{1,2}:\d{2}(:\d{2}(\.\d*)?)?\s*(Z|UTC|GMT|[+-]\d{2}:?\d{2})?$",
        "",
        item.value.strip(),
        flags=re.IGNORECASE,
    )
    try:
        return _parse_date(text)
    except ValueError as exc:
        raise InputFileError(
            path, f"DATE {item.value!r}: {exc}; write it as YYYY-MM-DD", line=item.line
        ) from None


def _parse_date(text: str) -> dt.date:
    """ISO and other unambiguous dates; see the module docstring."""
    if re.fullmatch(r"\d{8}", text):
        return dt.date(int(text[:4]), int(text[4:6]), int(text[6:]))
    tokens = re.findall(r"[A-Za-z]+|\d+", text)
    words = [t for t in tokens if t.isalpha()]
    numbers = [t for t in tokens if t.isdigit()]
    if not re.fullmatch(r"[A-Za-z0-9\s,./-]+", text) or len(tokens) != 3 or len(words) > 1:
        raise ValueError("not a date")
    if words:
        where = tokens.index(words[0])
        if where == 2:
            raise ValueError("not a date")
        year, day = numbers if where == 1 and len(numbers[0]) == 4 else numbers[::-1]
        return dt.date(_year(year), _month(words[0]), int(day))
    if len(numbers[0]) == 4:
        return dt.date(int(numbers[0]), int(numbers[1]), int(numbers[2]))
    if len(numbers[2]) != 4:
        raise ValueError("ambiguous order of day, month and a two-digit year")
    a, b = int(numbers[0]), int(numbers[1])
    if a != b and a <= 12 and b <= 12:
        raise ValueError(f"ambiguous: day {a} of month {b}, or day {b} of month {a}")
    day, month = (a, b) if a > 12 or a == b else (b, a)
    return dt.date(int(numbers[2]), month, day)


def _month(word: str) -> int:
    matches = [i for name, i in _MONTHS.items() if len(word) >= 3 and name.startswith(word.upper())]
    if len(matches) != 1:
        raise ValueError(f"{word!r} is not a month")
    return matches[0]


def _year(text: str) -> int:
    """A four-digit year, or a two-digit one as the latest such year not after today."""
    if len(text) not in (2, 4):
        raise ValueError(f"year {text!r}")
    if len(text) == 4:
        return int(text)
    this_year = dt.date.today().year
    return this_year - (this_year - int(text)) % 100


def _elevation(
    path: Path, header: Header
) -> tuple[tuple[float, Item] | None, tuple[str, Item] | None]:
    """(elevation m, its item) and (depth reference, its item), each when known."""
    reference = header.find(path, *REFERENCE_ITEMS)
    present = {m: i for m in ELEVATION_ITEMS if (i := header.find(path, m)) is not None}
    item = present.get("EREF")
    if item is None and reference is not None:
        item = present.get(
            REFERENCE_ELEVATION.get(reference.value.upper(), ""), present.get("ELEV")
        )
    elif item is None and len(present) > 1:
        raise InputFileError(
            path,
            f"elevations {', '.join(present)} are given but no DREF, LMF or DMF item says "
            "which one depths are measured from",
            line=max(i.line for i in present.values()),
        )
    elif item is None and present:
        item = next(iter(present.values()))
    depth: tuple[str, Item] | None = None
    if reference is not None:
        depth = (reference.value, reference)
    elif item is not None and (implied := ELEVATION_ITEMS[item.mnemonic]) is not None:
        depth = (implied, item)
    if item is None:
        return None, depth
    try:
        if not item.unit:
            raise UnitError(f"no unit: write e.g. '{item.mnemonic}.M  {item.value}'")
        factor = conversion_factor(item.unit, "length")
    except UnitError as exc:
        raise InputFileError(path, f"{item.mnemonic}: {exc}", line=item.line) from None
    return (_header_number(path, item) * factor, item), depth


# ---------------------------------------------------------------------------- writer


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


# ---------------------------------------------------------------------------- hooks


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="las",
            description="LAS 1.2/2.0 (and single-log 3.0) files: survey stations or raw "
            "sensor samples",
            kinds={"stations": Stations, "samples": RawSamples},
            read=read_las,
            sniff=sniff,
            options=LasOptions,
        )
    )


@hookimpl
def gyropipe_register_writers(register: Callable[[WriterDef], None]) -> None:
    register(
        WriterDef(
            name="las",
            description="numeric tables as LAS 2.0 with units, well metadata and north reference",
            extension="las",
            write=write_las,
        )
    )
